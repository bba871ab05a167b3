"""The site files shipped with the package (``matrix_core/site/sites/*.yaml``) and the MATRIX site.

``matrix_site()`` is where matrix-tracker's MATRIX defaults come from (``MATRIX_AREA`` and ``MATRIX_VIEWS``
in :mod:`matrix_core.datasets.matrix_conventions`, ``MATRIX_BLOCK``, the BEV cell size).
"""

from functools import lru_cache
from pathlib import Path

from matrix_core.site.load import load_site
from matrix_core.site.schema import Site

SITES_DIR = Path(__file__).resolve().parent / 'sites'
MATRIX_SITE = 'matrix'


def shipped_sites() -> tuple:
    """Names of the shipped site files (``matrix``, ``plaza``)."""
    return tuple(sorted(p.stem for p in SITES_DIR.glob('*.yaml')))


def site_path(name_or_path) -> Path:
    """The file a command's SITE argument names: a path, or the bare name of a shipped site."""
    path = Path(name_or_path)
    shipped = SITES_DIR / f'{name_or_path}.yaml'
    if not path.is_file() and path.parent == Path('.') and path.suffix == '' and shipped.is_file():
        return shipped
    if not path.is_file():
        raise FileNotFoundError(
            f'site file not found: {name_or_path} (a path, or a shipped site: {", ".join(shipped_sites())})'
        )
    return path


@lru_cache(maxsize=1)
def matrix_site() -> Site:
    """The shipped MATRIX site (read once)."""
    return load_site(SITES_DIR / f'{MATRIX_SITE}.yaml')
