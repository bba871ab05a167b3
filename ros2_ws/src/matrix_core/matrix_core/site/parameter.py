"""The ``site`` setting: one name, one meaning and one default for every node, launch file and command.

``site`` names a site file (docs/site-file.md): a path, or the name of a shipped site; the default is the
shipped MATRIX site, so a component given no site behaves as it always did. A settings dataclass takes it by
having a ``site`` field (:class:`SiteSettings`, or :func:`site_field` for a dataclass outside the
``Settings`` family), and the code that builds settings from flags, launch arguments or ROS parameters calls
:func:`follow_site` once:

- a field of :data:`~matrix_core.site.settings.SITE_FIELDS` (``area``, ``views``, ``exclude_boxes``,
  ``obstacle_boxes``, ``cell_m``) whose default is the MATRIX site's value stands for "the site's value": left
  at that default, it takes the named site's value (:func:`~matrix_core.site.settings.apply_site`); given
  explicitly, it wins;
- a field of the same name whose default is something else (a node's ``views``: the drones this process
  hosts, empty for the drone of its namespace) is a different setting and is left alone.

For the MATRIX site nothing changes: ``site:=matrix`` is the same as no site argument.
"""

import dataclasses
from dataclasses import dataclass, field
from functools import lru_cache

from matrix_core import topics
from matrix_core.settings import Settings
from matrix_core.site.load import SiteError, load_site
from matrix_core.site.schema import Site
from matrix_core.site.settings import SITE_FIELDS
from matrix_core.site.shipped import MATRIX_SITE, matrix_site, shipped_sites, site_path

SITE_HELP = (
    'site file (docs/site-file.md): a path or a shipped site ({shipped}); its area, drones, obstacles and BEV cell '
    'are the defaults of the settings that have them (given values win); default: the MATRIX site'
)


def site_field():
    """The ``site`` field of a settings dataclass (a fresh ``dataclasses.field`` each time)."""
    return field(default=MATRIX_SITE, metadata={'help': SITE_HELP.format(shipped=', '.join(shipped_sites()))})


SITE_REFERENCES_HELP = (
    "each drone's reference image and calibration are those the site file names (its references), for a site "
    'without a dataset folder beside it (matrix-tracker site init, a site dataset); the node\'s dataset folder '
    'parameter must then be empty'
)


def site_references_field():
    """The ``site_references`` field of a node's settings (register, calib, fuse: one meaning in each)."""
    return field(default=False, metadata={'help': SITE_REFERENCES_HELP})


@dataclass
class SiteSettings(Settings):
    """The site a component works on (module docstring)."""

    site: str = site_field()

    def check(self) -> None:
        if not isinstance(self.site, str) or not self.site.strip():
            raise ValueError(f'site must name a site file or a shipped site, got {self.site!r}')


@lru_cache(maxsize=16)
def _load(name: str) -> Site:
    return load_site(site_path(name))


def named_site(name: str) -> Site:
    """The site a ``site`` setting names (loaded and checked once per process); SiteError naming the file and
    the key, or a FileNotFoundError naming the shipped sites, when it cannot be used."""
    if name == MATRIX_SITE:
        return matrix_site()
    try:
        return _load(name)
    except FileNotFoundError as exc:
        raise SiteError(f'site {name!r}: {exc}') from None


def _same(a, b) -> bool:
    """Setting values equal, lists and tuples alike (numbers compared as numbers)."""
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def site_following_fields(cls, defaults: dict = None) -> tuple:
    """The fields of ``cls`` that follow the site: those of ``SITE_FIELDS`` whose default (``defaults[name]``,
    e.g. a launch file's own, else the dataclass's) is the MATRIX site's value."""
    matrix = matrix_site()
    out = []
    for f in dataclasses.fields(cls):
        if f.name not in SITE_FIELDS:
            continue
        if defaults is not None and f.name in defaults:
            default = defaults[f.name]
        elif f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            continue
        if _same(default, SITE_FIELDS[f.name](matrix)):
            out.append(f.name)
    return tuple(out)


def follow_site(settings, defaults: dict = None):
    """``settings`` with the site-following fields (:func:`site_following_fields`) that are still at their
    MATRIX default replaced by the values of the site its ``site`` field names; unchanged when it has no
    ``site`` field. SiteError when the site cannot be loaded."""
    name = getattr(settings, 'site', None)
    if name is None:
        return settings
    return with_site(settings, named_site(name), defaults)


def with_site(settings, site: Site, defaults: dict = None):
    """``settings`` (any settings dataclass, with or without a ``site`` field) with its site-following fields
    still at their MATRIX default replaced by ``site``'s values (:func:`follow_site` for a loaded site)."""
    matrix = matrix_site()
    changes = {}
    for f in site_following_fields(type(settings), defaults):
        if _same(getattr(settings, f), SITE_FIELDS[f](matrix)):
            changes[f] = SITE_FIELDS[f](site)
    if not changes or all(_same(v, getattr(settings, k)) for k, v in changes.items()):
        return settings
    try:
        return dataclasses.replace(settings, **changes)
    except (TypeError, ValueError) as exc:
        raise SiteError(f'{site.path}: its values do not fit {type(settings).__name__}: {exc}') from None


def check_drones(site: Site, drones, what: str) -> None:
    """SiteError naming every one of ``drones`` (names) that ``site`` does not have; ``what`` says where the
    names come from (``'views'``, ``'bag /data/run1'``)."""
    unknown = [d for d in drones if d not in site.drone_names]
    if unknown:
        which = 'drone' if len(unknown) == 1 else 'drones'
        raise SiteError(
            f'{what} names {which} {", ".join(unknown)}, which site {site.name} ({site.path}) does not have '
            f'(its drones: {", ".join(site.drone_names)}); give site:=... / --site for this recording, or add '
            f'the {which} to the site file'
        )


# The per-drone streams whose namespace names a drone of the recording: its images and its camera_info.
_DRONE_STREAMS = (topics.IMAGE_RAW, topics.IMAGE_COMPRESSED, topics.CAMERA_INFO, topics.GROUND_TRUTH_CAMERA_INFO)


def recorded_drones(topic_names) -> list:
    """The drones a recording's topics name, sorted: the namespace of every ``/<drone>/image_raw``,
    ``/<drone>/image/compressed`` and ``/<drone>/[ground_truth/]camera_info`` topic."""
    drones = set()
    for name in topic_names:
        parts = str(name).strip('/').split('/', 1)
        if len(parts) == 2 and parts[1] in _DRONE_STREAMS:
            drones.add(parts[0])
    return sorted(drones)


def check_bag_drones(site: Site, topic_names, bag) -> None:
    """SiteError naming the drones the recording at ``bag`` (its ``topic_names``) has and ``site`` does not:
    such a recording is of another site, and is refused before anything is played."""
    check_drones(site, recorded_drones(topic_names), f'bag {bag}')


def dataset_site(name, dataset, where: str = None) -> Site:
    """The site of a command's ``--site`` for ``dataset`` (a ``MultiviewDataset``): ``name`` None, the site the
    dataset names (a site dataset's ``site.yaml``), else the MATRIX site; given (a path or a shipped site),
    that site, which the dataset must agree with (:func:`check_dataset_site`, ``where`` default its folder)."""
    if name is None:
        return getattr(dataset, 'site', None) or matrix_site()
    site = named_site(name)
    check_dataset_site(site, dataset, where or str(dataset.root))
    return site


def check_dataset_site(site: Site, dataset, where: str) -> None:
    """SiteError, naming ``where`` (a flag and a folder) and each difference, when ``dataset``'s area is not
    ``site``'s or it has drones the site lacks (a dataset of some of the site's drones agrees)."""
    differ = []
    if len(dataset.area) != len(site.area) or any(
        abs(float(a) - float(b)) > 1e-6 for a, b in zip(dataset.area, site.area)
    ):
        differ.append(f'its area {[float(v) for v in dataset.area]} is not the area {list(site.area)}')
    unknown = [v for v in dataset.views if v not in site.drone_names]
    if unknown:
        differ.append(f'its drones {unknown} are not drones ({", ".join(site.drone_names)})')
    if differ:
        raise SiteError(
            f'{where}: {"; ".join(differ)} of site {site.name} ({site.path}); give --site the site of this data'
        )
