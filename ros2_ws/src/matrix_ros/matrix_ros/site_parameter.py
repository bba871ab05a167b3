"""The ``site`` parameter of a node (``matrix_core.site.parameter``), applied where its parameters are declared
(``matrix_ros.params.declare_settings``), once for every node.

The site is read first, from the parameters given (``-p site:=plaza``, a parameter file) or the defaults: the
fields that follow it then default to its values, so that every other parameter given still wins. A site
that cannot be loaded, or ``views`` naming a drone the site does not have, stops the node at start with the
error naming the file, the key or the drone.
"""

import dataclasses

from matrix_core.site.parameter import check_drones, follow_site, named_site


def site_defaults(cls, defaults, given: dict):
    """(defaults, Site) for a settings class ``cls`` with a ``site`` field: ``defaults`` (an instance of
    ``cls``, or None for the dataclass's) with the given or default site and the fields that follow it set to
    the site's values; (defaults, None) when ``cls`` has no ``site`` field."""
    if 'site' not in {f.name for f in dataclasses.fields(cls)}:
        return defaults, None
    defaults = defaults if defaults is not None else cls()
    name = given.get('site', defaults.site)
    if not isinstance(name, str):
        raise ValueError(f'parameter site is a string (a site file or a shipped site), got {name!r}')
    site = named_site(name)  # SiteError naming the file and the key
    return follow_site(dataclasses.replace(defaults, site=name)), site


def check_site_views(node, site, settings) -> None:
    """SiteError when the ``views`` of a node's ``settings`` name a drone that ``site`` does not have."""
    views = getattr(settings, 'views', None)
    if site is not None and views:
        check_drones(site, views, f'{node.get_fully_qualified_name()}: parameter views')
