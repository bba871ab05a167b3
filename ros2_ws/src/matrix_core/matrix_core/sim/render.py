"""CPU renderer: one view of the scene as a BGR image plus a per-pixel person-id buffer.

Pipeline (painter's algorithm, all OpenCV): sky; the ground texture warped through the view's ground
homography (``img_H_ground @ ground_H_tex``); building facades (textured quads, warped in their bounding
rectangle); checkerboards as exact anti-aliased projected squares (sub-pixel fixed-point vertices, so
OpenCV's corner detector finds the true corners); sun shadows of boxes and people (darkened ground);
then occluding boxes and pedestrians in a depth order
that is exact for vertical bodies against convex boxes (see :func:`_draw_order`).

Pedestrians are articulated (:mod:`~matrix_core.sim.person_model`): legs, arms, torso, neck and an
optional dress are convex hulls of projected rings, shaded darker on the side away from the light; the
head is a disc with hair.
The id buffer holds ``person_id + 1`` where a person is the front-most surface and 0 elsewhere.

Light, sky colour and shadow darkness come from the renderer's per-sequence
:class:`~matrix_core.sim.lighting.Lighting` (``Renderer.light``).

Convention: internal camera model (:class:`~matrix_core.geometry.camera.Camera`, ideal pinhole).
"""

import heapq
from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.sim.appearance import LIT, SHADED
from matrix_core.sim.lighting import DAY, UP
from matrix_core.sim.person_model import LIT_PARTS, PARTS, RING_ANGLES, body_rings, head_centers
from matrix_core.sim.raster import SHIFT, clip_half_plane_2d, clip_near, fixed, project_camera_points, to_camera
from matrix_core.sim.distractors import shadow_hulls
from matrix_core.sim.scene import box_faces

LIT_WINDOW_RED = 200  # facade texels this red are lit windows (textures.facade_texture): they glow at dusk


@dataclass
class People:
    """Pedestrians to draw. ids: (N,) int; positions: (N, 2) metres (the midpoint between the feet);
    heights: (N,) metres; colors: (N, 3 or 4, 3) uint8 BGR of shirt (or dress), trousers (or legs), skin
    and hair (default: dark); leg_radius: the annotation / collision radius (metres, not drawn);
    body_radius: unused (kept for callers). headings: (N,) walking direction, radians (default +x);
    phases: (N,) gait phase, radians; swings: (N,) leg swing amplitude, radians (default 0: standing);
    dress: (N,) bool (a short cone from the waist instead of trousers). See :mod:`person_model`."""

    ids: np.ndarray
    positions: np.ndarray
    heights: np.ndarray
    colors: np.ndarray
    leg_radius: float = 0.16
    body_radius: float = 0.22
    headings: np.ndarray = None
    phases: np.ndarray = None
    swings: np.ndarray = None
    dress: np.ndarray = None

    def pose(self) -> tuple:
        """(headings, phases, swings, dress) with the defaults filled in, each (N,)."""
        n = len(self.ids)
        zeros = np.zeros(n)
        return (
            zeros if self.headings is None else np.asarray(self.headings, float),
            zeros if self.phases is None else np.asarray(self.phases, float),
            zeros if self.swings is None else np.asarray(self.swings, float),
            np.zeros(n, bool) if self.dress is None else np.asarray(self.dress, bool),
        )


def _in_front_of_box(point_xy, bounds, camera_xy) -> bool:
    """Whether a vertical body at ``point_xy`` is in front of the box ``bounds`` seen from ``camera_xy``:
    true when some side plane has both the camera and the body on its outer side (the box then lies
    entirely beyond that plane, so it can never cover the body)."""
    x0, y0, x1, y1 = bounds
    (px, py), (cx, cy) = point_xy, camera_xy
    return (cx > x1 and px > x1) or (cx < x0 and px < x0) or (cy > y1 and py > y1) or (cy < y0 and py < y0)


def _draw_order(items, camera_xy) -> list:
    """Indices of ``items`` (dicts with kind, depth, rect, xy/bounds) in a valid painter's order.

    Only pairs whose image rectangles overlap are constrained: vertical bodies (kind 'person' or 'round', a
    vertical distractor) among themselves far to near, body/box and box/box by :func:`_in_front_of_box`.
    Ties and unconstrained items go far to near (Kahn's algorithm).
    """
    n = len(items)
    rects = np.array([it['rect'] for it in items]).reshape(n, 4)
    overlap = (
        (rects[:, None, 0] < rects[None, :, 2])
        & (rects[None, :, 0] < rects[:, None, 2])
        & (rects[:, None, 1] < rects[None, :, 3])
        & (rects[None, :, 1] < rects[:, None, 3])
    )
    after = [[] for _ in range(n)]
    indeg = [0] * n
    for a, b in zip(*np.nonzero(np.triu(overlap, 1))):
        ia, ib = items[a], items[b]
        if ia['kind'] != 'box' and ib['kind'] != 'box':
            first, second = (a, b) if ia['depth'] >= ib['depth'] else (b, a)
        elif ia['kind'] == 'box' and ib['kind'] == 'box':
            first, second = (b, a) if _in_front_of_box(ia['xy'], ib['bounds'], camera_xy) else (a, b)
        else:
            box, other = (a, b) if ia['kind'] == 'box' else (b, a)
            in_front = _in_front_of_box(items[other]['xy'], items[box]['bounds'], camera_xy)
            first, second = (box, other) if in_front else (other, box)
        after[first].append(second)
        indeg[second] += 1
    heap = [(-items[i]['depth'], i) for i in range(n) if indeg[i] == 0]
    heapq.heapify(heap)
    order = []
    while heap:
        _, i = heapq.heappop(heap)
        order.append(i)
        for j in after[i]:
            indeg[j] -= 1
            if indeg[j] == 0:
                heapq.heappush(heap, (-items[j]['depth'], j))
    if len(order) < n:  # a cycle (should not happen for disjoint boxes): fall back to plain depth order
        rest = sorted(set(range(n)) - set(order), key=lambda i: -items[i]['depth'])
        order += rest
    return order


class Renderer:
    """Renders views of a :class:`~matrix_core.sim.scene.Scene` under ``light`` (a
    :class:`~matrix_core.sim.lighting.Lighting`; shading code reads ``renderer.light``)."""

    def __init__(self, scene, light=DAY):
        self.scene = scene
        self.light = light
        self._lit = {}  # id(texture) -> the texture under self.light (built once per sequence)

    def _lit_texture(self, texture, gain, emissive_red: int = 256) -> np.ndarray:
        """``texture`` (H, W, 3) uint8 times the BGR ``gain`` (3,), cached: the light is fixed per sequence.
        Texels with red >= ``emissive_red`` emit light (lit windows) and keep their colour."""
        if self.light.plain:
            return texture
        key = id(texture)
        if key not in self._lit:
            lit = cv2.multiply(texture, tuple(float(g) for g in gain))
            glow = texture[..., 2] >= emissive_red
            lit[glow] = texture[glow]
            self._lit[key] = (texture, lit)
        return self._lit[key][1]  # the entry keeps the texture alive, so its id stays unique

    def render(self, camera, people: People = None) -> tuple:
        """Render one view.

        Args:
            camera: internal :class:`Camera` (its width/height set the image size).
            people: pedestrians to draw, or None for the empty scene (reference images).

        Returns:
            image: (H, W, 3) uint8 BGR; ids: (H, W) uint16, ``person_id + 1`` of the visible person, else 0.
        """
        W, H = camera.width, camera.height
        img = np.empty((H, W, 3), dtype=np.uint8)
        ids = np.zeros((H, W), dtype=np.uint16)
        self._sky_and_ground(camera, img)
        self._facades(camera, img)
        self._boards(camera, img)
        self._shadows(camera, img, people)
        self._boxes_and_people(camera, img, ids, people)
        return img, ids

    # ----- background ------------------------------------------------------------------------------
    def _sky_and_ground(self, camera, img):
        """Fill every pixel: the ground texture below the horizon (warped only in the rows that can show
        ground), sky elsewhere."""
        H, W = img.shape[:2]
        # The ground shows where the pixel ray K^-1 (u, v, 1) (z = 1 in the camera) points down by more than
        # 0.01 in world z; nearer the horizon it is beyond the texture (and behind the facades) anyway.
        ray_z = (camera.R.T @ np.linalg.inv(camera.K))[2]
        rect = np.array([[-1, -1], [W, -1], [W, H], [-1, H]], dtype=float)
        ground = clip_half_plane_2d(rect, -ray_z - np.array([0.0, 0.0, 0.01]))
        top = H if len(ground) < 3 else int(np.clip(np.floor(ground[:, 1].min()), 0, H))
        sky_bgr = self.light.sky
        img[:top] = sky_bgr
        if top >= H:
            return
        tex, t_H_g = self.scene.ground_level_for(camera)
        tex = self._lit_texture(tex, self.light.gain(UP))
        rows_H_img = np.array([[1.0, 0, 0], [0, 1.0, -top], [0, 0, 1.0]])  # image rows top.. -> 0..
        rows_H_tex = rows_H_img @ camera.img_H_ground(0.0) @ np.linalg.inv(t_H_g)
        cv2.warpPerspective(
            tex,
            rows_H_tex,
            (W, H - top),
            dst=img[top:],
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=sky_bgr,
        )
        sky = clip_half_plane_2d(rect, ray_z + np.array([0.0, 0.0, 0.01]))
        if len(sky) >= 3:
            cv2.fillConvexPoly(img, fixed(sky), sky_bgr, cv2.LINE_AA, SHIFT)

    def _facades(self, camera, img):
        H, W = img.shape[:2]
        c = camera.center
        visible, normal_out = [], {}
        for f in self.scene.facades:
            normal = np.cross(f.corners[3] - f.corners[0], f.corners[1] - f.corners[0])  # towards the inside
            if normal @ (c - f.corners[0]) <= 0:  # seen from behind
                continue
            normal_out[id(f)] = normal / np.linalg.norm(normal)
            poly = clip_near(to_camera(camera, f.corners))
            if len(poly) >= 3:
                visible.append((-float(np.mean(poly[:, 2])), f, project_camera_points(camera.K, poly)))
        for _, f, uv in sorted(visible, key=lambda v: v[0]):
            x0, y0 = np.maximum(np.floor(uv.min(axis=0)).astype(int), 0)
            x1, y1 = np.minimum(np.ceil(uv.max(axis=0)).astype(int) + 1, [W, H])
            if x1 <= x0 or y1 <= y0:
                continue
            H_tex = camera.P @ f.world_from_tex()
            shift = np.array([[1.0, 0, -x0], [0, 1.0, -y0], [0, 0, 1.0]])
            gain = self.light.gain(normal_out[id(f)]) * self.light.facade_level
            texture = self._lit_texture(f.texture, gain, emissive_red=LIT_WINDOW_RED)
            patch = cv2.warpPerspective(
                texture, shift @ H_tex, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
            )
            mask = np.zeros((y1 - y0, x1 - x0), dtype=np.uint8)
            cv2.fillConvexPoly(mask, fixed(uv - [x0, y0]), 255, cv2.LINE_8, SHIFT)
            roi = img[y0:y1, x0:x1]
            np.copyto(roi, patch, where=mask[..., None].astype(bool))

    def _boards(self, camera, img):
        white, black = (235, 235, 235), (25, 25, 25)  # paint on the ground: lit like the ground texture
        if not self.light.plain:
            white, black = (tuple(float(v) for v in np.multiply(c, self.light.gain(UP))) for c in (white, black))
        for board in self.scene.boards:
            (nx, ny), s = board.squares_xy, board.square_m
            gx, gy = np.meshgrid(board.origin[0] + np.arange(nx + 1) * s, board.origin[1] + np.arange(ny + 1) * s)
            grid = np.stack([gx, gy, np.full(gx.shape, board.z)], axis=-1)  # (n+1, n+1, 3), [j, i]
            cam = to_camera(camera, grid)
            if cam[..., 2].max() < 0.3:
                continue
            outline = clip_near(cam[[0, 0, -1, -1], [0, -1, -1, 0]])
            if len(outline) < 3:
                continue
            cv2.fillConvexPoly(img, fixed(project_camera_points(camera.K, outline)), white, cv2.LINE_AA, SHIFT)
            ok = cam[..., 2] > 0.3
            uv = project_camera_points(camera.K, np.where(ok[..., None], cam, 1.0))
            for j in range(ny):
                for i in range((j + board.dark_parity) % 2, nx, 2):  # black when i + j + dark_parity is even
                    if ok[j, i] and ok[j, i + 1] and ok[j + 1, i + 1] and ok[j + 1, i]:
                        quad = uv[[j, j, j + 1, j + 1], [i, i + 1, i + 1, i]]
                        cv2.fillConvexPoly(img, fixed(quad), black, cv2.LINE_AA, SHIFT)

    def _shadows(self, camera, img, people):
        """Darken the ground under the sun's shadows of boxes and people (hulls of their footprint and
        their top outline projected along the sun direction onto z = 0); only in the shadows' bounding box."""
        sun = self.light.direction
        offset = -sun[:2] / sun[2]  # ground displacement per metre of height
        hulls = []
        for bounds, height, _ in self.scene.boxes:
            x0, y0, x1, y1 = bounds
            foot = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
            hulls.append(np.concatenate([foot, foot + offset * height]))
        if people is not None:
            ring = 0.22 * np.stack([np.cos(RING_ANGLES), np.sin(RING_ANGLES)], axis=1)
            for xy, h in zip(people.positions, people.heights):  # a slim body: 0.22 m at the feet, less above
                hulls.append(np.concatenate([xy + ring, xy + ring * 0.6 + offset * h]))
        polys = []
        for pts in hulls:
            hull = cv2.convexHull(pts.astype(np.float32)).reshape(-1, 2).astype(float)
            cam = clip_near(to_camera(camera, np.c_[hull, np.zeros(len(hull))]))
            if len(cam) >= 3:
                polys.append(project_camera_points(camera.K, cam))
        polys += self._round_shadows(camera, offset)
        if not polys:
            return
        H, W = img.shape[:2]
        allp = np.concatenate(polys)
        x0, y0 = np.maximum(np.floor(allp.min(axis=0)).astype(int), 0)
        x1, y1 = np.minimum(np.ceil(allp.max(axis=0)).astype(int) + 1, [W, H])
        if x1 <= x0 or y1 <= y0:
            return
        mask = np.zeros((y1 - y0, x1 - x0), dtype=np.uint8)
        for uv in polys:
            cv2.fillConvexPoly(mask, fixed(uv - [x0, y0]), 1, cv2.LINE_8, SHIFT)
        roi = img[y0:y1, x0:x1]
        dark = cv2.LUT(roi, (np.arange(256) * self.light.shadow_mult_256 >> 8).astype(np.uint8))
        cv2.copyTo(dark, mask, roi)  # in place: roi is a view of img

    def _round_shadows(self, camera, offset) -> list:
        """Image polygons of the vertical distractors' shadows in view (their ground hulls are static, so
        they are computed once per light)."""
        key = (tuple(np.round(offset, 9)), len(self.scene.rounds))
        if getattr(self, '_round_shadow_key', None) != key:
            self._round_shadow_key = key
            hulls = [
                cv2.convexHull(p.astype(np.float32)).reshape(-1, 2).astype(float)
                for p in shadow_hulls(self.scene.rounds, offset)
            ]
            self._round_shadow_hulls = [np.c_[h, np.zeros(len(h))] for h in hulls]  # (M, 3) on z = 0
        H, W = camera.height, camera.width
        out = []
        for hull in self._round_shadow_hulls:
            cam = clip_near(to_camera(camera, hull))
            if len(cam) >= 3:
                uv = project_camera_points(camera.K, cam)
                lo, hi = uv.min(axis=0), uv.max(axis=0)
                if hi[0] >= 0 and hi[1] >= 0 and lo[0] <= W and lo[1] <= H:
                    out.append(uv)
        return out

    # ----- occluders and people ----------------------------------------------------------------------
    def _box_polys(self, camera, bounds, height, cfg):
        """[(uv polygon, BGR)] of the camera-facing faces of a box (stripes as extra bands)."""
        c = camera.center
        out = []
        base = np.asarray(cfg.color, dtype=float)
        for corners, normal in box_faces(bounds, height):
            if normal @ (c - corners[0]) <= 0:
                continue
            shade = self.light.color(base, normal)
            faces = [(corners, shade)]
            if cfg.stripes and normal[2] == 0:
                for z0 in np.arange(0.5, height, 1.0):
                    band = corners.copy()
                    band[[0, 1], 2], band[[2, 3], 2] = z0, min(z0 + 0.5, height)
                    faces.append((band, shade * 0.6))
            for poly, color in faces:
                cam = clip_near(to_camera(camera, poly))
                if len(cam) >= 3:
                    out.append((project_camera_points(camera.K, cam), tuple(float(v) for v in color)))
        return out

    def _person_polys(self, camera, people: People):
        """Per person: (depth, rect, [(kind, geometry, BGR)]) or None when behind the camera/outside;
        'poly'/'lit' geometry is a fixed-point (:data:`SHIFT`) int32 hull, 'circle' is (centre, radius).

        Parts are drawn far to near within a person (far leg, near leg, dress, far arm, torso, neck, near
        arm, head, hair); each limb is filled in its shaded colour, then its lit and camera-facing half
        (the hull of the ring points whose normal faces both the light and the camera) in its lit colour
        ('lit' parts colour the image only, the id buffer already has the whole limb).
        """
        headings, phases, swings, dress = people.pose()
        rings, centers, normals = body_rings(people.positions, people.heights, headings, phases, swings)
        cam = to_camera(camera, rings)  # (N, K, R, 3)
        head_c, head_r_m = head_centers(people.positions, people.heights)
        hair_c = head_c + np.c_[np.zeros((len(head_c), 2)), 0.2 * head_r_m]
        head_cam = to_camera(camera, np.stack([head_c, hair_c], axis=1))  # (N, 2, 3)
        sun = self.light.direction
        light_xy = sun[:2] / max(float(np.linalg.norm(sun[:2])), 1e-9)
        facing = np.einsum('nkrd,nkrd->nkr', normals, camera.center[:2] - rings[..., :2]) > 0
        lit = (normals @ light_xy > 0.0) & facing
        part_depth = np.linalg.norm(centers - camera.center, axis=2)  # (N, K)
        n_rings = np.where(dress, PARTS['dress'][1], PARTS['dress'][0])
        used = np.arange(cam.shape[1])[None, :] < n_rings[:, None]  # (N, K): dress rings only with a dress
        z_min = np.minimum(np.where(used, cam[..., 2].min(axis=2), np.inf).min(axis=1), head_cam[:, 0, 2])
        ok = z_min >= 0.3
        safe = np.where(ok[:, None, None, None], cam, 1.0)
        uv = project_camera_points(camera.K, safe)  # (N, K, R, 2)
        uv_fixed = np.round(np.clip(uv, -1e5, 1e5) * (1 << SHIFT)).astype(np.int32)  # for OpenCV (shift)
        head_uv = project_camera_points(camera.K, np.where(ok[:, None, None], head_cam, 1.0))  # (N, 2, 2)
        head_r = camera.K[0, 0] * head_r_m / np.where(ok, head_cam[:, 0, 2], 1.0)
        big = np.where(used[..., None, None], uv, np.nan).reshape(len(uv), -1, 2)
        lo = np.minimum(np.nanmin(big, axis=1), head_uv[:, 0] - head_r[:, None])
        hi = np.maximum(np.nanmax(big, axis=1), head_uv[:, 0] + head_r[:, None])
        ok &= (hi[:, 0] >= 0) & (hi[:, 1] >= 0) & (lo[:, 0] <= camera.width) & (lo[:, 1] <= camera.height)
        lit_ok = {
            name: lit[:, a:b].any(axis=2).all(axis=1) & (lit[:, a:b].sum(axis=(1, 2)) >= 3)
            for name, (a, b) in PARTS.items()
            if name in LIT_PARTS
        }
        depth = np.linalg.norm(camera.center[:2] - people.positions, axis=1)
        colors = people.colors.astype(float)
        if colors.shape[1] < 4:  # no hair colour given: dark hair
            colors = np.concatenate([colors, np.full((len(colors), 1, 3), 25.0)], axis=1)
        if not self.light.plain:  # albedos under DAY: the sequence's light level and colour
            colors = colors * self.light.tint
        shaded, lit_col = (colors * SHADED).tolist(), (colors * LIT).tolist()
        head_col, hair_col = (colors[:, 2] * (SHADED + LIT) / 2).tolist(), colors[:, 3].tolist()
        out = []
        for k in range(len(people.ids)):
            if not ok[k]:
                out.append(None)
                continue
            d = part_depth[k]
            far_leg, near_leg = ('leg_l', 'leg_r') if d[1] > d[3] else ('leg_r', 'leg_l')
            far_arm, near_arm = ('arm_l', 'arm_r') if d[5] > d[7] else ('arm_r', 'arm_l')
            order = [(far_leg, 1), (near_leg, 1)] + ([('dress', 0)] if dress[k] else [])
            order += [(far_arm, 0), ('torso', 0), ('neck', 2), (near_arm, 0)]  # colour index
            parts = []
            for name, c in order:
                a, b = PARTS[name]
                parts.append(('poly', cv2.convexHull(uv_fixed[k, a:b].reshape(-1, 2)), shaded[k][c]))
                if name in LIT_PARTS and lit_ok[name][k]:
                    parts.append(('lit', cv2.convexHull(uv_fixed[k, a:b][lit[k, a:b]]), lit_col[k][c]))
            parts.append(('circle', (head_uv[k, 0], head_r[k]), head_col[k]))
            parts.append(('circle', (head_uv[k, 1], head_r[k] * 0.8), hair_col[k]))
            out.append((float(depth[k]), (*lo[k], *hi[k]), parts))
        return out

    def _rounds_in_view(self, camera) -> list:
        """The vertical distractors whose bounding cylinder may show in the image (a cheap vectorised
        cull: axis end points in front of the camera, projected extent overlapping the image)."""
        rounds = self.scene.rounds
        if not rounds:
            return []
        if getattr(self, '_round_axes', None) is None or len(self._round_axes) != len(rounds):
            self._round_axes = np.array([[[*r.xy, 0.0], [*r.xy, r.top]] for r in rounds])  # (N, 2, 3)
            self._round_radii = np.array([r.radius for r in rounds])
        cam = to_camera(camera, self._round_axes)
        z = cam[..., 2]
        front = (z > 0.3).all(axis=1)
        uv = project_camera_points(camera.K, np.where(front[:, None, None], cam, 1.0))
        r_px = camera.K[0, 0] * self._round_radii / np.maximum(z.min(axis=1), 0.3)
        lo, hi = uv.min(axis=1) - r_px[:, None], uv.max(axis=1) + r_px[:, None]
        keep = front & (hi[:, 0] >= 0) & (hi[:, 1] >= 0) & (lo[:, 0] <= camera.width) & (lo[:, 1] <= camera.height)
        return [rounds[i] for i in np.flatnonzero(keep)]

    def _round_parts(self, camera, rnd):
        """(rect, [(kind, geometry, BGR)]) of a vertical distractor (cylinders as hulls of their end circles,
        spheres as discs with a highlight toward the light), or None when (partly) behind the camera."""
        ring = np.stack([np.cos(RING_ANGLES), np.sin(RING_ANGLES)], axis=1)
        to_cam = camera.center[:2] - rnd.xy
        to_cam /= max(float(np.linalg.norm(to_cam)), 1e-9)
        sun = self.light.direction
        light_xy = sun[:2] / max(float(np.linalg.norm(sun[:2])), 1e-9)
        side = 0.55 + 0.4 * max(0.0, float(light_xy @ to_cam))  # brightness of the camera-facing side
        tint = np.ones(3) if self.light.plain else self.light.tint  # the sequence's light level and colour
        parts, pts = [], []
        for radius, z0, z1, color in rnd.cylinders:
            circle = rnd.xy + radius * ring
            world = np.concatenate([np.c_[circle, np.full(len(ring), z0)], np.c_[circle, np.full(len(ring), z1)]])
            cam = to_camera(camera, world)
            if cam[:, 2].min() < 0.3:
                return None
            uv = project_camera_points(camera.K, cam)
            pts.append(uv)
            hull = cv2.convexHull(uv.astype(np.float32)).reshape(-1, 2)
            parts.append(('poly', hull, tuple(float(c) * side * t for c, t in zip(color, tint))))
        for z, radius, color in rnd.spheres:
            for center, r, shade in (
                (np.array([*rnd.xy, z]), radius, 0.6),
                (np.array([*rnd.xy, z]) + 0.35 * radius * sun, 0.55 * radius, 1.0),
            ):
                c_cam = to_camera(camera, center)
                if c_cam[2] < 0.3 + radius:
                    return None
                uv = project_camera_points(camera.K, c_cam)
                r_px = camera.K[0, 0] * r / c_cam[2]
                pts.append(np.array([uv - r_px, uv + r_px]))
                parts.append(('circle', (uv, r_px), tuple(float(c) * shade * t for c, t in zip(color, tint))))
        allp = np.concatenate(pts)
        return (*allp.min(axis=0), *allp.max(axis=0)), parts

    def _boxes_and_people(self, camera, img, ids, people):
        cam_xy = camera.center[:2]
        items = []
        H, W = img.shape[:2]
        for rnd in self._rounds_in_view(camera):
            entry = self._round_parts(camera, rnd)
            if entry is None or entry[0][2] < 0 or entry[0][3] < 0 or entry[0][0] > W or entry[0][1] > H:
                continue
            items.append(
                {
                    'kind': 'round',
                    'depth': float(np.linalg.norm(cam_xy - rnd.xy)),
                    'rect': entry[0],
                    'parts': entry[1],
                    'xy': rnd.xy,
                    'id': 0,
                }
            )
        for bounds, height, cfg in self.scene.boxes:
            polys = self._box_polys(camera, bounds, height, cfg)
            if not polys:
                continue
            allp = np.concatenate([p for p, _ in polys])
            center = np.array([(bounds[0] + bounds[2]) / 2, (bounds[1] + bounds[3]) / 2])
            items.append(
                {
                    'kind': 'box',
                    'depth': float(np.linalg.norm(cam_xy - center)),
                    'bounds': bounds,
                    'xy': center,
                    'rect': (*allp.min(axis=0), *allp.max(axis=0)),
                    'polys': polys,
                }
            )
        if people is not None and len(people.ids):
            for k, entry in enumerate(self._person_polys(camera, people)):
                if entry is not None:
                    depth, rect, parts = entry
                    items.append(
                        {
                            'kind': 'person',
                            'depth': depth,
                            'rect': rect,
                            'parts': parts,
                            'xy': people.positions[k],
                            'id': int(people.ids[k]) + 1,
                        }
                    )
        if not items:
            return
        for i in _draw_order(items, cam_xy):
            it = items[i]
            if it['kind'] == 'box':
                for uv, color in it['polys']:
                    pts = fixed(uv)
                    cv2.fillConvexPoly(img, pts, color, cv2.LINE_AA, SHIFT)
                    cv2.fillConvexPoly(ids, pts, 0, cv2.LINE_8, SHIFT)
                continue
            line = cv2.LINE_AA if it['kind'] == 'round' else cv2.LINE_8
            for kind, geom, color in it['parts']:
                if kind in ('poly', 'lit'):  # people: fixed-point int32 hulls; round objects: float pixels
                    pts = geom if geom.dtype == np.int32 else fixed(geom)
                    cv2.fillConvexPoly(img, pts, color, line, SHIFT)
                    if kind == 'poly':
                        cv2.fillConvexPoly(ids, pts, it['id'], cv2.LINE_8, SHIFT)
                else:
                    (u, v), r = geom
                    center = (int(round(u * (1 << SHIFT))), int(round(v * (1 << SHIFT))))
                    radius = max(1, int(round(r * (1 << SHIFT))))
                    cv2.circle(img, center, radius, color, -1, line, SHIFT)
                    cv2.circle(ids, center, radius, it['id'], -1, cv2.LINE_8, SHIFT)
