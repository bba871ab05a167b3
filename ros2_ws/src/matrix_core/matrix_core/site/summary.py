"""What ``matrix-tracker site check`` prints: a site's area, grid, drones, boards, obstacles and references."""

from matrix_core.site.load import SiteError
from matrix_core.site.references import reference_camera, reference_files, reference_root
from matrix_core.site.schema import ReferenceSource, Site


def _m(v: float) -> str:
    return f'{v:g}'


def _reference_lines(site: Site) -> tuple:
    """(lines, per-drone reference camera height or None, number of drones whose references are missing)."""
    if site.references is ReferenceSource.SIMULATE:
        return ['references: to be simulated (references.source: simulate); none on disk yet'], {}, 0
    try:
        root = reference_root(site)
    except SiteError as exc:
        return [f'references: not found: {str(exc).split(": ", 2)[-1]}'], {}, len(site.drones)
    lines = [f'references: files under {root} (references.root: {site.references_root_text})']
    heights, missing = {}, 0
    for files in reference_files(site):
        if files.found:
            try:
                heights[files.drone] = float(reference_camera(site, site.drone(files.drone)).center[2])
                lines.append(f'  {files.drone}: found')
            except SiteError as exc:
                missing += 1
                lines.append(f'  {files.drone}: unreadable: {str(exc).split(": ", 2)[-1]}')
        else:
            missing += 1
            lines.append(f'  {files.drone}: missing {", ".join(str(p) for p in files.missing)}')
    return lines, heights, missing


def format_site(site: Site) -> tuple:
    """(text, number of drones whose reference files are missing or unreadable) of a loaded site."""
    x0, y0, x1, y1 = site.area
    rows, cols = site.grid_shape()
    ref_lines, heights, missing = _reference_lines(site)
    out = [
        f'site {site.name}: {site.path}',
        f'area: x {_m(x0)}..{_m(x1)} m, y {_m(y0)}..{_m(y1)} m ({_m(x1 - x0)} x {_m(y1 - y0)} m)',
        f'BEV cell: {_m(site.cell_m)} m, grid {rows} x {cols} cells (rows x cols, no margin)',
        f'drones: {len(site.drones)}',
    ]
    for d in site.drones:
        w, h = d.camera.image_size
        parts = [f'{w}x{h} px', f'fx {d.camera.K[0, 0]:.1f} ({d.camera.hfov_deg:.1f} deg wide)']
        if d.altitude_m is not None:
            parts.append(f'altitude {_m(d.altitude_m)} m')
        if d.home_xy is not None:
            parts.append(f'home ({_m(d.home_xy[0])}, {_m(d.home_xy[1])})')
        if d.name in heights:
            parts.append(f'reference camera at {heights[d.name]:.2f} m')
        out.append(f'  {d.name}: ' + ', '.join(parts))
    out.append(f'boards: {len(site.boards) or "none"}')
    for b in site.boards:
        centre = b.points([(b.nx - 1) / 2], [(b.ny - 1) / 2])[0]
        out.append(
            f'  {b.name}: {b.nx + 1} x {b.ny + 1} squares of {_m(b.square)} m, centre '
            f'({centre[0]:.2f}, {centre[1]:.2f}, {centre[2]:.2f})'
        )
    out.append(f'obstacles: {len(site.obstacles) or "none"}')
    for o in site.obstacles:
        ox0, oy0, ox1, oy1 = o.footprint
        out.append(f'  {o.name}: x {_m(ox0)}..{_m(ox1)} m, y {_m(oy0)}..{_m(oy1)} m, {_m(o.height)} m high')
    out += ref_lines
    return '\n'.join(out), missing
