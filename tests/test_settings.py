"""Settings dataclasses become CLI flags with the same names and defaults."""

import argparse
from dataclasses import dataclass, field

import pytest

from matrix_core.settings import add_settings_arguments, settings_fields, settings_from_namespace


@dataclass
class Example:
    rate: float = field(default=2.0, metadata={'help': 'frames per second'})
    name: str = 'x'
    enabled: bool = True
    views: list[str] = field(default_factory=list)

    def __post_init__(self):
        if self.rate <= 0:
            raise ValueError('rate must be positive')


def parse(*argv):
    parser = argparse.ArgumentParser()
    add_settings_arguments(parser, Example)
    return settings_from_namespace(Example, parser.parse_args(argv))


def test_defaults_and_overrides():
    assert parse() == Example()
    s = parse('--rate', '0.5', '--enabled', 'false', '--views', 'D1', 'D3')
    assert (s.rate, s.enabled, s.views) == (0.5, False, ['D1', 'D3'])
    assert parse('--enabled').enabled is True and parse('--enabled', 'no').enabled is False
    assert [f[0] for f in settings_fields(Example)] == ['rate', 'name', 'enabled', 'views']
    assert settings_fields(Example)[0][3] == 'frames per second'


def test_validation_runs():
    with pytest.raises(ValueError, match='positive'):
        parse('--rate', '-1')


def test_launch_argument_strings_round_trip():
    """Launch arguments are strings: defaults written by setting_to_string parse back to the defaults."""
    from matrix_core.settings import setting_to_string, settings_from_strings

    texts = {name: setting_to_string(default) for name, _, default, _ in settings_fields(Example)}
    assert texts == {'rate': '2.0', 'name': 'x', 'enabled': 'true', 'views': ''}
    assert settings_from_strings(Example, texts) == Example()
    for views in ('D1,D3', '[D1, D3]', "['D1','D3']"):
        assert settings_from_strings(Example, {'views': views}).views == ['D1', 'D3']
    s = settings_from_strings(Example, {'rate': '0.5', 'enabled': 'False'})
    assert (s.rate, s.enabled, s.name) == (0.5, False, 'x')
    with pytest.raises(ValueError, match='Example.enabled'):
        settings_from_strings(Example, {'enabled': 'maybe'})
    with pytest.raises(ValueError, match='positive'):
        settings_from_strings(Example, {'rate': '-1'})
