"""A site's values in a component's settings: the fields every settings dataclass names the same way.

``apply_site(settings, site)`` replaces, in any settings dataclass, the fields it has among :data:`SITE_FIELDS`
(``area``, ``views``, ``exclude_boxes``, ``obstacle_boxes``, ``cell_m``) with the site's values and leaves
every other field as it is. For the shipped MATRIX site it changes nothing (the defaults are read from it).
"""

import dataclasses

from matrix_core.site.schema import Site

# settings field -> the site's value in that field's form
SITE_FIELDS = {
    'area': lambda site: list(site.area),  # x_min y_min x_max y_max (m)
    'views': lambda site: list(site.drone_names),  # the drones, in the site's order
    'exclude_boxes': lambda site: site.obstacle_boxes,  # groups x0 y0 x1 y1 height (m)
    'obstacle_boxes': lambda site: site.obstacle_boxes,
    'cell_m': lambda site: site.cell_m,  # BEV cell (m)
}


def site_fields(settings_cls) -> tuple:
    """The names of the fields of ``settings_cls`` that :func:`apply_site` sets."""
    return tuple(f.name for f in dataclasses.fields(settings_cls) if f.name in SITE_FIELDS)


def apply_site(settings, site: Site):
    """A copy of the settings dataclass ``settings`` with the site's area, drones, obstacles and cell in the
    fields it has of :data:`SITE_FIELDS` (validated again by the dataclass)."""
    return dataclasses.replace(settings, **{name: SITE_FIELDS[name](site) for name in site_fields(type(settings))})
