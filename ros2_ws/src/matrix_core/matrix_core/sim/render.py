"""CPU renderer: one view of the scene as a BGR image plus a per-pixel person-id buffer.

Pipeline (painter's algorithm, all OpenCV): sky; the ground texture warped through the view's ground
homography (``img_H_ground @ ground_H_tex``); building facades (textured quads, warped in their bounding
rectangle); checkerboards as exact anti-aliased projected squares (sub-pixel fixed-point vertices, so
OpenCV's corner detector finds the true corners); sun shadows of boxes and people (darkened ground);
then occluding boxes and pedestrians in a depth order
that is exact for vertical bodies against convex boxes (see :func:`_draw_order`).

Pedestrians are a legs cylinder, a torso cylinder (convex hulls of projected circles) and a spherical head.
The id buffer holds ``person_id + 1`` where a person is the front-most surface and 0 elsewhere.

Convention: internal camera model (:class:`~matrix_core.geometry.camera.Camera`, ideal pinhole).
"""

import heapq
from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.sim.raster import (SHIFT, clip_half_plane_2d, clip_near, fixed, project_camera_points,
                                    to_camera)
from matrix_core.sim.distractors import shadow_hulls
from matrix_core.sim.scene import box_faces

SKY = (235, 206, 175)
LIGHT = np.array([0.45, 0.3, 0.84]) / np.linalg.norm([0.45, 0.3, 0.84])
RING_ANGLES = np.linspace(0.0, 2 * np.pi, 10, endpoint=False)
LEG_TOP, TORSO_BOTTOM, TORSO_TOP, HEAD_CENTER, HEAD_RADIUS = 0.48, 0.44, 0.82, 0.915, 0.075  # x height


@dataclass
class People:
    """Pedestrians to draw. ids: (N,) int; positions: (N, 2) metres; heights: (N,) metres;
    colors: (N, 3, 3) uint8 BGR of shirt, trousers and skin; radii: (leg, body) metres."""

    ids: np.ndarray
    positions: np.ndarray
    heights: np.ndarray
    colors: np.ndarray
    leg_radius: float = 0.16
    body_radius: float = 0.22


def _rings(people: People) -> np.ndarray:
    """(N, 4, R, 3) world points on the circles bounding legs and torso."""
    n = len(people.ids)
    cos, sin = np.cos(RING_ANGLES), np.sin(RING_ANGLES)
    radii = np.array([people.leg_radius, people.leg_radius, people.body_radius * 0.85, people.body_radius])
    heights = np.array([0.0, LEG_TOP, TORSO_BOTTOM, TORSO_TOP])[None, :] * people.heights[:, None]
    pts = np.empty((n, 4, len(RING_ANGLES), 3))
    pts[..., 0] = people.positions[:, None, None, 0] + radii[None, :, None] * cos
    pts[..., 1] = people.positions[:, None, None, 1] + radii[None, :, None] * sin
    pts[..., 2] = heights[..., None]
    return pts


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
    overlap = ((rects[:, None, 0] < rects[None, :, 2]) & (rects[None, :, 0] < rects[:, None, 2])
               & (rects[:, None, 1] < rects[None, :, 3]) & (rects[None, :, 1] < rects[:, None, 3]))
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
    """Renders views of a :class:`~matrix_core.sim.scene.Scene`."""

    def __init__(self, scene):
        self.scene = scene

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
        img[:top] = SKY
        if top >= H:
            return
        tex, t_H_g = self.scene.ground_level_for(camera)
        rows_H_img = np.array([[1.0, 0, 0], [0, 1.0, -top], [0, 0, 1.0]])  # image rows top.. -> 0..
        rows_H_tex = rows_H_img @ camera.img_H_ground(0.0) @ np.linalg.inv(t_H_g)
        cv2.warpPerspective(tex, rows_H_tex, (W, H - top), dst=img[top:], flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_CONSTANT, borderValue=SKY)
        sky = clip_half_plane_2d(rect, ray_z + np.array([0.0, 0.0, 0.01]))
        if len(sky) >= 3:
            cv2.fillConvexPoly(img, fixed(sky), SKY, cv2.LINE_AA, SHIFT)

    def _facades(self, camera, img):
        H, W = img.shape[:2]
        c = camera.center
        visible = []
        for f in self.scene.facades:
            normal = np.cross(f.corners[3] - f.corners[0], f.corners[1] - f.corners[0])  # towards the inside
            if normal @ (c - f.corners[0]) <= 0:  # seen from behind
                continue
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
            patch = cv2.warpPerspective(f.texture, shift @ H_tex, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR,
                                        borderMode=cv2.BORDER_REPLICATE)
            mask = np.zeros((y1 - y0, x1 - x0), dtype=np.uint8)
            cv2.fillConvexPoly(mask, fixed(uv - [x0, y0]), 255, cv2.LINE_8, SHIFT)
            roi = img[y0:y1, x0:x1]
            np.copyto(roi, patch, where=mask[..., None].astype(bool))

    def _boards(self, camera, img):
        for board in self.scene.boards:
            n, s = board.squares, board.square_m
            g = np.arange(n + 1) * s
            gx, gy = np.meshgrid(board.origin[0] + g, board.origin[1] + g)
            grid = np.stack([gx, gy, np.full(gx.shape, board.z)], axis=-1)  # (n+1, n+1, 3), [j, i]
            cam = to_camera(camera, grid)
            if cam[..., 2].max() < 0.3:
                continue
            outline = clip_near(cam[[0, 0, -1, -1], [0, -1, -1, 0]])
            if len(outline) < 3:
                continue
            cv2.fillConvexPoly(img, fixed(project_camera_points(camera.K, outline)), (235, 235, 235),
                               cv2.LINE_AA, SHIFT)
            ok = cam[..., 2] > 0.3
            uv = project_camera_points(camera.K, np.where(ok[..., None], cam, 1.0))
            for j in range(n):
                for i in range(j % 2, n, 2):  # square (i, j) black when i + j is even
                    if ok[j, i] and ok[j, i + 1] and ok[j + 1, i + 1] and ok[j + 1, i]:
                        quad = uv[[j, j, j + 1, j + 1], [i, i + 1, i + 1, i]]
                        cv2.fillConvexPoly(img, fixed(quad), (25, 25, 25), cv2.LINE_AA, SHIFT)

    def _shadows(self, camera, img, people):
        """Darken the ground under the sun's shadows of boxes and people (hulls of their footprint and
        their top outline projected along :data:`LIGHT` onto z = 0); only in the shadows' bounding box."""
        offset = -LIGHT[:2] / LIGHT[2]  # ground displacement per metre of height
        hulls = []
        for bounds, height, _ in self.scene.boxes:
            x0, y0, x1, y1 = bounds
            foot = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
            hulls.append(np.concatenate([foot, foot + offset * height]))
        if people is not None:
            ring = 0.25 * np.stack([np.cos(RING_ANGLES), np.sin(RING_ANGLES)], axis=1)
            for xy, h in zip(people.positions, people.heights):
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
        sel = mask.view(bool)
        roi[sel] = (roi[sel].astype(np.uint16) * 160 >> 8).astype(np.uint8)  # 62 % brightness

    def _round_shadows(self, camera, offset) -> list:
        """Image polygons of the vertical distractors' shadows in view (their ground hulls are static, so
        they are computed once per light)."""
        key = (tuple(np.round(offset, 9)), len(self.scene.rounds))
        if getattr(self, '_round_shadow_key', None) != key:
            self._round_shadow_key = key
            hulls = [cv2.convexHull(p.astype(np.float32)).reshape(-1, 2).astype(float)
                     for p in shadow_hulls(self.scene.rounds, offset)]
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
            shade = base * (0.55 + 0.45 * max(0.0, float(normal @ LIGHT)))
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
        """Per person: (depth, rect, [(kind, geometry, BGR)]) or None when behind the camera/outside."""
        rings = _rings(people)
        cam = to_camera(camera, rings)
        head_c = np.concatenate([people.positions, (HEAD_CENTER * people.heights)[:, None]], axis=1)
        head_cam = to_camera(camera, head_c)
        H, W = camera.height, camera.width
        out = []
        for k in range(len(people.ids)):
            if cam[k, ..., 2].min() < 0.3 or head_cam[k, 2] < 0.3:
                out.append(None)
                continue
            uv = project_camera_points(camera.K, cam[k])  # (4, R, 2)
            head_uv = project_camera_points(camera.K, head_cam[k])
            head_r = camera.K[0, 0] * HEAD_RADIUS * people.heights[k] / head_cam[k, 2]
            lo = np.minimum(uv.reshape(-1, 2).min(axis=0), head_uv - head_r)
            hi = np.maximum(uv.reshape(-1, 2).max(axis=0), head_uv + head_r)
            if hi[0] < 0 or hi[1] < 0 or lo[0] > W or lo[1] > H:
                out.append(None)
                continue
            shirt, trousers, skin = (tuple(int(v) for v in c) for c in people.colors[k])
            legs = cv2.convexHull(np.concatenate([uv[0], uv[1]]).astype(np.float32)).reshape(-1, 2)
            torso = cv2.convexHull(np.concatenate([uv[2], uv[3]]).astype(np.float32)).reshape(-1, 2)
            parts = [('poly', legs, trousers), ('poly', torso, shirt), ('circle', (head_uv, head_r), skin)]
            depth = float(np.linalg.norm(camera.center[:2] - people.positions[k]))
            out.append((depth, (*lo, *hi), parts))
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
        light_xy = LIGHT[:2] / max(float(np.linalg.norm(LIGHT[:2])), 1e-9)
        side = 0.55 + 0.4 * max(0.0, float(light_xy @ to_cam))  # brightness of the camera-facing side
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
            parts.append(('poly', hull, tuple(float(c) * side for c in color)))
        for z, radius, color in rnd.spheres:
            for center, r, shade in ((np.array([*rnd.xy, z]), radius, 0.6),
                                     (np.array([*rnd.xy, z]) + 0.35 * radius * LIGHT, 0.55 * radius, 1.0)):
                c_cam = to_camera(camera, center)
                if c_cam[2] < 0.3 + radius:
                    return None
                uv = project_camera_points(camera.K, c_cam)
                r_px = camera.K[0, 0] * r / c_cam[2]
                pts.append(np.array([uv - r_px, uv + r_px]))
                parts.append(('circle', (uv, r_px), tuple(float(c) * shade for c in color)))
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
            items.append({'kind': 'round', 'depth': float(np.linalg.norm(cam_xy - rnd.xy)), 'rect': entry[0],
                          'parts': entry[1], 'xy': rnd.xy, 'id': 0})
        for bounds, height, cfg in self.scene.boxes:
            polys = self._box_polys(camera, bounds, height, cfg)
            if not polys:
                continue
            allp = np.concatenate([p for p, _ in polys])
            center = np.array([(bounds[0] + bounds[2]) / 2, (bounds[1] + bounds[3]) / 2])
            items.append({'kind': 'box', 'depth': float(np.linalg.norm(cam_xy - center)), 'bounds': bounds,
                          'xy': center, 'rect': (*allp.min(axis=0), *allp.max(axis=0)), 'polys': polys})
        if people is not None and len(people.ids):
            for k, entry in enumerate(self._person_polys(camera, people)):
                if entry is not None:
                    depth, rect, parts = entry
                    items.append({'kind': 'person', 'depth': depth, 'rect': rect, 'parts': parts,
                                  'xy': people.positions[k], 'id': int(people.ids[k]) + 1})
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
                if kind == 'poly':
                    pts = fixed(geom)
                    cv2.fillConvexPoly(img, pts, color, line, SHIFT)
                    cv2.fillConvexPoly(ids, pts, it['id'], cv2.LINE_8, SHIFT)
                else:
                    (u, v), r = geom
                    center = (int(round(u * (1 << SHIFT))), int(round(v * (1 << SHIFT))))
                    radius = max(1, int(round(r * (1 << SHIFT))))
                    cv2.circle(img, center, radius, color, -1, line, SHIFT)
                    cv2.circle(ids, center, radius, it['id'], -1, cv2.LINE_8, SHIFT)
