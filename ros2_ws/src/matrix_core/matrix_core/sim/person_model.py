"""Articulated pedestrian: world-space rings of the body parts of N people in a walking pose.

Every part (leg, arm, torso, neck, dress) is the convex hull of two or three horizontal rings (ellipses
oriented by the walking heading); the renderer projects the rings and fills each part's hull, so a part is
a convex polygon like a capsule seen from the camera. The head is a sphere (a circle in the image).

Proportions are fractions of the body height at a reference height of 1.75 m (widths scale with height).
The walking phase advances with the distance walked (one gait cycle per :data:`STRIDE` x height); legs
swing by up to :data:`SWING_DEG` around the hip and arms swing opposite; people standing still have their
legs together. The person's ground position is the midpoint between the feet (at every phase).

Convention: internal world metres, z up; headings are radians from +x; rings are (N, K, R, 3).
"""

import numpy as np

RING_ANGLES = np.linspace(0.0, 2 * np.pi, 10, endpoint=False)
STRIDE = 0.7  # metres walked per gait cycle, x body height
SWING_DEG = 25.0  # leg swing amplitude at walking speed; arms swing 0.7 of it
FULL_SWING_SPEED = 0.8  # m/s: slower people swing less, standing people (speed ~0) not at all
REF_HEIGHT = 1.75

# Heights (x body height) and half-widths (metres at 1.75 m, scaled with height).
HIP_Z, WAIST_Z, CHEST_Z, SHOULDER_Z, NECK_TOP_Z = 0.50, 0.60, 0.76, 0.815, 0.88
HEAD_RADIUS = 0.066  # x height: 0.115 m at 1.75 m; the head's top is the body height
HIP_HALF = 0.085  # lateral offset of each hip joint
LEG_R_TOP, LEG_R_FOOT = 0.075, 0.055
ARM_HALF, ARM_LEN, ARM_R_TOP, ARM_R_HAND = 0.19, 0.36, 0.045, 0.04  # ARM_LEN x height
TORSO_RINGS = ((HIP_Z, 0.095, 0.15), (CHEST_Z, 0.12, 0.19), (SHOULDER_Z, 0.10, 0.17))  # (z, depth, width)
NECK_R = 0.05
DRESS_TOP, DRESS_HEM_Z, DRESS_HEM_R = (WAIST_Z, 0.10, 0.15), 0.34, 0.21

# Ring layout per person: index ranges of each part (legs and arms: left then right).
PARTS = {
    'leg_l': (0, 2),
    'leg_r': (2, 4),
    'arm_l': (4, 6),
    'arm_r': (6, 8),
    'torso': (8, 11),
    'neck': (11, 13),
    'dress': (13, 15),
}
N_RINGS = 15
LIT_PARTS = ('leg_l', 'leg_r', 'torso', 'dress')  # drawn with a lit side (arms, neck: too thin to show)


def gait_phase(walked, heights, ids) -> np.ndarray:
    """(N,) radians: the walking phase from the distance walked (N,) metres; a per-id offset (golden
    ratio sequence, no random draw) keeps people out of step."""
    offset = (np.asarray(ids) * 0.618034) % 1.0
    return 2 * np.pi * (np.asarray(walked) / (STRIDE * np.asarray(heights)) + offset)


def swing_amplitude(speeds) -> np.ndarray:
    """(N,) radians of leg swing for walking speeds (N,) m/s: full at walking pace, 0 when standing."""
    return np.radians(SWING_DEG) * np.clip(np.asarray(speeds) / FULL_SWING_SPEED, 0.0, 1.0)


def max_reach(height: float) -> tuple:
    """(horizontal, vertical) metres: the farthest any drawn point can be from the person's vertical axis
    (a swinging foot or hand, or the shoulders) and the top of the head, for a person of ``height``; used
    to bound how far the drawn body may exceed the 0.16 m x 1.8 m annotation cylinder."""
    s = height / REF_HEIGHT
    amp = np.radians(SWING_DEG)
    foot = HIP_Z * height * np.sin(amp) + LEG_R_FOOT * s
    hand = np.hypot(ARM_HALF * s, ARM_LEN * height * np.sin(0.7 * amp)) + ARM_R_HAND * s
    return float(max(foot, hand, np.hypot(ARM_HALF * s, ARM_R_TOP * s) + ARM_R_TOP * s, DRESS_HEM_R * s)), float(height)


def body_rings(positions, heights, headings, phases, swings) -> tuple:
    """World rings of every part of N people.

    Args:
        positions: (N, 2) ground points (midpoint between the feet); heights: (N,) metres;
        headings: (N,) walking direction, radians; phases: (N,) gait phase; swings: (N,) leg amplitude.

    Returns:
        rings: (N, N_RINGS, R, 3) world points; centers: (N, N_RINGS, 3) ring centres;
        normals: (N, N_RINGS, R, 2) horizontal outward unit normals of the ring points (for shading).
    """
    positions = np.asarray(positions, float).reshape(-1, 2)
    n = len(positions)
    h = np.asarray(heights, float).reshape(n)
    s = h / REF_HEIGHT
    fwd = np.stack([np.cos(headings), np.sin(headings)], axis=1)  # (N, 2)
    lat = np.stack([-fwd[:, 1], fwd[:, 0]], axis=1)  # left of the heading
    leg = swings * np.sin(phases)  # (N,) left leg angle forward; the right leg mirrors it
    arm = -0.7 * leg

    centers = np.zeros((n, N_RINGS, 3))
    depth = np.zeros((n, N_RINGS))  # ring half-axis along the heading (metres)
    width = np.zeros((n, N_RINGS))  # ... and across it

    def put(k, xy, z, d, w):
        centers[:, k, :2], centers[:, k, 2], depth[:, k], width[:, k] = xy, z, d, w

    hip_z, leg_len = HIP_Z * h, HIP_Z * h
    sh_z = (SHOULDER_Z - 0.02) * h
    for side, (k_leg, k_arm), sign in (('l', (0, 4), 1.0), ('r', (2, 6), -1.0)):
        hip = positions + sign * HIP_HALF * s[:, None] * lat
        foot = hip + (sign * np.sin(leg) * leg_len)[:, None] * fwd  # feet symmetric about the position
        foot -= sign * 0.5 * HIP_HALF * s[:, None] * lat  # feet slightly closer together than the hips
        put(k_leg, hip, hip_z, LEG_R_TOP * s, LEG_R_TOP * s)
        put(k_leg + 1, foot, 0.0, LEG_R_FOOT * s, LEG_R_FOOT * s)
        shoulder = positions + sign * ARM_HALF * s[:, None] * lat
        a = sign * arm
        hand = shoulder + (np.sin(a) * ARM_LEN * h)[:, None] * fwd + sign * 0.03 * s[:, None] * lat
        put(k_arm, shoulder, sh_z, ARM_R_TOP * s, ARM_R_TOP * s)
        put(k_arm + 1, hand, sh_z - np.cos(a) * ARM_LEN * h, ARM_R_HAND * s, ARM_R_HAND * s)
    for j, (z, d, w) in enumerate(TORSO_RINGS):
        put(8 + j, positions, z * h, d * s, w * s)
    put(11, positions, (SHOULDER_Z - 0.02) * h, NECK_R * s, NECK_R * s)
    put(12, positions, NECK_TOP_Z * h, NECK_R * s * 0.9, NECK_R * s * 0.9)
    z, d, w = DRESS_TOP
    put(13, positions, z * h, d * s, w * s)
    put(14, positions, DRESS_HEM_Z * h, DRESS_HEM_R * s, DRESS_HEM_R * s)

    cos, sin = np.cos(RING_ANGLES), np.sin(RING_ANGLES)
    offs = (
        depth[..., None, None] * cos[:, None] * fwd[:, None, None, :]
        + width[..., None, None] * sin[:, None] * lat[:, None, None, :]
    )  # (N, K, R, 2)
    rings = np.empty((n, N_RINGS, len(RING_ANGLES), 3))
    rings[..., :2] = centers[:, :, None, :2] + offs
    rings[..., 2] = centers[:, :, None, 2]
    normals = (
        cos[:, None] * fwd[:, None, None, :] * width[..., None, None]
        + sin[:, None] * lat[:, None, None, :] * depth[..., None, None]
    )
    normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-9)
    return rings, centers, normals


def head_centers(positions, heights) -> tuple:
    """(N, 3) head centres and (N,) head radii, metres (the top of the head is the body height)."""
    h = np.asarray(heights, float)
    r = HEAD_RADIUS * h
    return np.concatenate([np.asarray(positions, float).reshape(-1, 2), (h - r)[:, None]], axis=1), r
