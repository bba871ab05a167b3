"""One parameter name, one meaning, in every process: the nodes of a process are given one parameter set
(``matrix_bringup.drone``: register and calib), so a name that two of their settings classes declare must
have the same type, default and help in both. The same holds for the classes one node's settings are
composed of (fuse: wiring, image boxes, fusion, restarts, tracker): a base that declared a name again with
another default would silently win over the other."""

import dataclasses
import typing

import pytest

from matrix_bev_tracker.settings import FuseNodeSettings
from matrix_bringup import drone
from matrix_calib.settings import CalibNodeSettings
from matrix_register.settings import RegisterNodeSettings

PROCESSES = {'drone': drone.HOSTED_SETTINGS, 'fuse': (FuseNodeSettings,)}


def declared_fields(cls) -> dict:
    """name -> [(declaring class, type, default, help)] over every dataclass in the MRO of ``cls`` that
    declares the field itself."""
    out = {}
    for klass in cls.__mro__:
        if not dataclasses.is_dataclass(klass):
            continue
        hints = typing.get_type_hints(klass)
        own = vars(klass).get('__annotations__', {})
        for f in dataclasses.fields(klass):
            if f.name not in own:
                continue
            default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
            out.setdefault(f.name, []).append((klass.__name__, hints[f.name], default, f.metadata.get('help', '')))
    return out


def conflicts(classes) -> dict:
    """name -> its declarations, for each name declared with more than one (type, default, help) by the
    dataclasses ``classes`` are composed of."""
    seen = {}
    for cls in classes:
        for name, declarations in declared_fields(cls).items():
            for decl in declarations:
                if decl not in seen.setdefault(name, []):
                    seen[name].append(decl)
    return {name: decls for name, decls in seen.items() if len({(repr(t), repr(d), h) for _, t, d, h in decls}) > 1}


def test_the_drone_process_hosts_register_and_calib():
    assert set(drone.HOSTED_SETTINGS) == {RegisterNodeSettings, CalibNodeSettings}


@pytest.mark.parametrize('process', sorted(PROCESSES))
def test_a_shared_parameter_name_has_one_type_default_and_help(process):
    found = conflicts(PROCESSES[process])
    assert not found, f'{process}: parameters with more than one meaning: {found}'


def test_a_name_with_two_meanings_is_found():
    """The check itself: two classes of one process that both declare ``seed``, with other defaults."""

    @dataclasses.dataclass
    class Fit:
        seed: int = dataclasses.field(default=0, metadata={'help': 'seed of the fit'})
        views: list[str] = dataclasses.field(default_factory=list, metadata={'help': 'drones'})

    @dataclasses.dataclass
    class Search:
        seed: int = dataclasses.field(default=1, metadata={'help': 'seed of the search'})
        views: list[str] = dataclasses.field(default_factory=list, metadata={'help': 'drones'})

    assert set(conflicts((Fit, Search))) == {'seed'}
    assert conflicts((Fit, Fit)) == {}
