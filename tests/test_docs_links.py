"""Every relative link in README.md and docs/*.md points at a file or folder of the repository.

A page moved or renamed without its links is a broken front door; links to web addresses and in-page anchors
are not checked (no network here, and anchors follow headings that change with the text)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md'))]
# [text](target) and ![alt](target); the target ends at the first space or closing parenthesis
LINK = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)(?:\s+"[^"]*")?\)')


def relative_links(page):
    """The relative link targets of a markdown page, without their #anchor, outside code blocks."""
    text = re.sub(r'```.*?```', '', page.read_text(encoding='utf-8'), flags=re.S)
    for target in LINK.findall(text):
        if re.match(r'^[a-z][a-z0-9+.-]*:', target) or target.startswith('#'):
            continue
        yield target.split('#', 1)[0]


@pytest.mark.parametrize('page', PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_relative_links_resolve(page):
    broken = [t for t in relative_links(page) if not (page.parent / t).exists()]
    assert not broken, f'{page.relative_to(ROOT)}: broken relative link(s) {broken}'


def test_the_link_pattern_finds_links():
    # the check above must not pass by finding nothing: the README links into docs/
    assert any(t.startswith('docs/') for t in relative_links(ROOT / 'README.md'))
