"""Settings of the registration component (CLI flags of ``matrix-tracker register`` and ROS parameters
of the ``register`` node, same names and defaults)."""

from dataclasses import dataclass, field

from matrix_core.site.shipped import matrix_site
from matrix_core.sync.stamp_restart import RestartSettings

# The real MATRIX scene's central block, internal world metres: x0, y0, x1, y1 (footprint), height; the
# obstacles of the shipped MATRIX site file.
MATRIX_BLOCK = matrix_site().obstacle_boxes


@dataclass
class RegisterSettings(RestartSettings):
    backend: str = field(
        default='sift',
        metadata={
            'help': 'feature backend: sift, gftt_affnet_hardnet, gftt_affnet_hardtfeat, gftt_affnet_sift '
            '(see matrix_core.register.backends.BACKENDS)'
        },
    )
    scale: float = field(
        default=0.25,
        metadata={'help': 'images are resized by this factor before feature extraction (0.25 = 480x270 for 1920x1080)'},
    )
    max_features: int = field(
        default=4000,
        metadata={
            'help': 'features kept per current image (strongest first); the reference keeps reference_max_features'
        },
    )
    reference_max_features: int = field(
        default=16000,
        metadata={'help': 'features detected on the reference image before the ground mask (extracted once, cached)'},
    )
    contrast_threshold: float = field(
        default=0.005,
        metadata={'help': 'SIFT contrastThreshold; the OpenCV default 0.04 finds almost nothing on the plaza concrete'},
    )
    ratio: float = field(default=0.8, metadata={'help': "Lowe's ratio test threshold tau (both directions)"})
    matcher: str = field(
        default='brute',
        metadata={
            'help': 'nearest-neighbour search: brute (exact, one distance matrix; faster here than flann at up to a '
            'few thousand features) or flann (approximate KD-trees)'
        },
    )
    estimator: str = field(
        default='magsac',
        metadata={
            'help': "robust homography estimator: magsac (default: OpenCV's USAC_MAGSAC, deterministic and the more "
            "accurate with few or noisy matches, so the live graph gives the same homographies on every "
            "replay) or ransac (the MATRIX paper's plain RANSAC, seeded by `registration_seed`; its run-to-run "
            "variation is what the paper's 10 runs measure)"
        },
    )
    homography_ransac_px: float = field(
        default=3.0, metadata={'help': 'inlier threshold in FULL-resolution pixels of the reference image'}
    )
    ransac_iterations: int = field(default=5000, metadata={'help': 'maximum robust-estimator iterations'})
    min_inliers: int = field(default=15, metadata={'help': 'fewer inliers than this -> status failed'})
    ground_only: bool = field(
        default=True, metadata={'help': 'keep only reference features whose back-projection lies on the scene ground'}
    )
    ground_margin_m: float = field(
        default=0.0,
        metadata={'help': 'grow the ground area (from the dataset) by this many metres on every side for the mask'},
    )
    exclude_boxes: list[float] = field(
        default_factory=lambda: list(MATRIX_BLOCK),
        metadata={
            'help': 'obstacles to mask out, groups of 5 numbers: x0 y0 x1 y1 height (internal world metres); '
            'default: the MATRIX central block'
        },
    )
    scene_from_dataset: bool = field(
        default=True,
        metadata={
            'help': "take exclude_boxes and ground_margin_m from the dataset's matrix_tracker_meta.json when it "
            'states them (simulated folders: block, pillars, flat ground up to the buildings); the real '
            'MATRIX sample has none and keeps the configured values'
        },
    )
    gate_max_shape_error: float = field(
        default=0.02,
        metadata={
            'help': 'sanity gate: largest deviation of the implied ground homography from a rigid camera '
            '(column norm ratio and non-orthogonality of K^-1 H) for a fit with gate_shape_inliers inliers'
        },
    )
    gate_shape_inliers: int = field(
        default=100,
        metadata={
            'help': 'with fewer inliers n the shape tolerance grows as sqrt(gate_shape_inliers / n): the noise of '
            'a homography fitted to n points falls as 1/sqrt(n)'
        },
    )
    gate_max_area_ratio: float = field(
        default=4.0,
        metadata={
            'help': 'sanity gate: the ground area warped into the current image may shrink/grow by at most this '
            'factor against the reference'
        },
    )
    gate_max_height_change_m: float = field(
        default=4.0, metadata={'help': 'sanity gate: largest change of the implied camera height against the reference'}
    )
    gate_max_step_m: float = field(
        default=3.0,
        metadata={
            'help': 'sanity gate: largest jump of the implied camera centre between consecutive registered frames'
        },
    )
    rekey_confidence: float = field(
        default=0.1, metadata={'help': 'confidence below which a frame counts as weak for re-keying'}
    )
    rekey_after: int = field(
        default=3,
        metadata={
            'help': 're-key to the last well-registered frame after this many weak or failed frames in a row '
            '(0 = never)'
        },
    )
    retry_reference_every: int = field(
        default=10,
        metadata={
            'help': 'while re-keyed, try the original reference again every this many frames, and at once when a '
            'chained frame is weak; it takes over again when good (0 = never)'
        },
    )
    good_confidence: float = field(
        default=0.25,
        metadata={'help': 'a frame with at least this confidence (and passing the gate) may become a key frame'},
    )
    mode: str = field(
        default='reference',
        metadata={
            'help': "reference: every frame registered to the reference by features (the paper's way); track: "
            'frames between anchors follow the previous frame by optical flow on its ground corners, '
            "refined against the anchor's corners (register/flow_tracking.py); anchors (full "
            'registrations) on the first frame, every reanchor_every frames, after a failure and when the '
            'chain is doubted'
        },
    )
    reanchor_every: int = field(
        default=10,
        metadata={
            'help': 'mode track: a full registration every this many frames (1 = every frame; 0 = only on the '
            'first frame, after failures and when the chain is doubted)'
        },
    )
    flow_corners: int = field(
        default=2000,
        metadata={'help': 'mode track: corners detected on each anchor at the reduced scale, before the ground mask'},
    )
    track_refine_scale: float = field(
        default=0.5,
        metadata={
            'help': "mode track: the refinement against the anchor runs on the image resized by this factor (0.5 = "
            '960x540 for 1920x1080; at least `scale`, which the flow step uses): corners located twice as '
            'finely as at 480x270 doubt fewer chains and fit tighter (docs/registration.md)'
        },
    )
    anchor_by_flow: bool = field(
        default=True,
        metadata={
            'help': 'mode track: an anchor is first tried by flow against the reference image itself (its ground '
            "corners refined in the current frame warped by the chain's prediction, or followed from the "
            'reference on the first frame): one hop to the reference like a full registration, at the cost '
            'of a tracked frame; features are described and matched only when that fails'
        },
    )
    track_min_inliers: int = field(
        default=40,
        metadata={
            'help': 'mode track: a frame whose refinement against the anchor has fewer inliers doubts the chain '
            '(a full registration follows)'
        },
    )
    anchor_search_margin_px: float = field(
        default=40.0,
        metadata={
            'help': "mode track: the anchor that follows a doubted chain describes features only where the chain's "
            "prediction puts the reference's ground, grown by this many full-resolution pixels (the whole "
            'image when that fails; 0 = always the whole image; register/search_region.py)'
        },
    )
    registration_seed: int = field(
        default=0,
        metadata={
            'help': 'random seed of the ransac estimator: the same seed repeats its homographies, other seeds '
            'draw other samples (magsac is deterministic and ignores it)'
        },
    )

    def check(self) -> None:
        from matrix_core.register.backends import BACKENDS

        if self.backend not in BACKENDS:
            raise ValueError(f'unknown backend {self.backend!r}; choose one of {sorted(BACKENDS)}')
        for name in ('scale', 'track_refine_scale'):
            if not 0.05 <= getattr(self, name) <= 1.0:
                raise ValueError(f'{name} must be in [0.05, 1], got {getattr(self, name)}')
        if not 0.0 < self.ratio <= 1.0:
            raise ValueError(f'ratio must be in (0, 1], got {self.ratio}')
        if self.matcher not in ('flann', 'brute'):
            raise ValueError(f'matcher must be flann or brute, got {self.matcher!r}')
        if self.estimator not in ('ransac', 'magsac'):
            raise ValueError(f'estimator must be ransac or magsac, got {self.estimator!r}')
        if self.mode not in ('reference', 'track'):
            raise ValueError(f'mode must be reference or track, got {self.mode!r}')
        if self.reanchor_every < 0:
            raise ValueError(f'reanchor_every must be >= 0, got {self.reanchor_every}')
        if len(self.exclude_boxes) % 5:
            raise ValueError(f'exclude_boxes needs groups of 5 numbers, got {len(self.exclude_boxes)}')
        if self.gate_shape_inliers < 1 or self.retry_reference_every < 0:
            raise ValueError('gate_shape_inliers must be >= 1 and retry_reference_every >= 0')
        for name in (
            'max_features',
            'reference_max_features',
            'min_inliers',
            'ransac_iterations',
            'flow_corners',
            'track_min_inliers',
        ):
            if getattr(self, name) < 4:
                raise ValueError(f'{name} must be at least 4')
        if self.anchor_search_margin_px < 0:
            raise ValueError(f'anchor_search_margin_px must be >= 0, got {self.anchor_search_margin_px}')
        if self.homography_ransac_px <= 0 or self.gate_max_area_ratio <= 1.0:
            raise ValueError('homography_ransac_px must be > 0 and gate_max_area_ratio > 1')
