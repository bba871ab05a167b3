"""Site files: everything site-specific (ground area, BEV cell, drones and their cameras, boards, obstacles,
references) in one YAML file per site, loaded strictly (docs/site-file.md).

- :mod:`~matrix_core.site.schema`: the dataclasses (:class:`Site`, :class:`DroneSpec`, ...);
- :mod:`~matrix_core.site.load`: the strict loader (:func:`load_site`, :class:`SiteError`);
- :mod:`~matrix_core.site.references`: the reference files on disk (:func:`require_references`);
- :mod:`~matrix_core.site.shipped`: the shipped sites, :func:`matrix_site`;
- :mod:`~matrix_core.site.summary`: what ``matrix-tracker site check`` prints;
- :mod:`~matrix_core.site.settings`: a site's values in any component's settings (:func:`apply_site`).
"""

from matrix_core.site.load import SiteError, load_site
from matrix_core.site.schema import DroneSpec, ReferenceSource, Site
from matrix_core.site.shipped import matrix_site, site_path

__all__ = ['DroneSpec', 'ReferenceSource', 'Site', 'SiteError', 'load_site', 'matrix_site', 'site_path']
