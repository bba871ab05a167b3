"""Settings of the calibration component: CLI flags of ``matrix-tracker calibrate`` and ROS parameters of
the ``calib`` node, same names and defaults (see ``matrix_core.settings``)."""

from dataclasses import dataclass, field

from matrix_core.sync.stamp_restart import RestartSettings


@dataclass
class CalibSettings(RestartSettings):
    config: str = field(
        default='',
        metadata={
            'help': 'scene YAML: boards, intrinsics, optional initial poses (see matrix_calib/config/*.yaml); '
            'empty = the MATRIX sample config shipped with matrix_core'
        },
    )
    px_per_square: float = field(
        default=10.0,
        metadata={
            'help': 'each board is searched in a view rectified with the prior pose, squares this many pixels wide'
        },
    )
    margin_cells: float = field(
        default=3.0,
        metadata={'help': 'squares of margin around the board in the rectified view (covers the prior error)'},
    )
    initial_margin_cells: float = field(
        default=10.0,
        metadata={'help': 'margin while the prior is still the configured/reference pose (it can be metres off)'},
    )
    motion_scale: float = field(
        default=0.5,
        metadata={
            'help': 'image scale of the ORB ground homography from the previous (or reference) image to the '
            'current one, which carries the prior into the current image (0 = off)'
        },
    )
    motion_features: int = field(
        default=3000,
        metadata={
            'help': 'ORB features per image for that homography (the brute-force matching time grows with their square)'
        },
    )
    motion_matcher: str = field(
        default='brute',
        metadata={
            'help': 'matching of the ORB features of that homography: brute, or lsh (FLANN LSH: 40 instead of 150 ms, '
            'real sample 30 instead of 32 of 40 views ok, worst pose 0.33 instead of 0.17 deg)'
        },
    )
    global_shift_scale: float = field(
        default=0.125,
        metadata={'help': 'image scale of the phase correlation used when the ground homography fails (0 = off)'},
    )
    pattern_size: int = field(
        default=5,
        metadata={'help': 'smallest grid (n x n inner corners) findChessboardCornersSB looks for; LARGER grows it'},
    )
    max_pieces_per_board: int = field(
        default=1,
        metadata={'help': 'detection is repeated after masking each found piece, at most this many times per board'},
    )
    detect_accuracy: bool = field(
        default=True,
        metadata={
            'help': 'findChessboardCornersSB with CALIB_CB_ACCURACY: about 40 % slower, but without it the worst '
            'poses on simulated sequences are several times worse (measured 0.49 deg / 33 cm against '
            '0.17 deg / 9 cm)'
        },
    )
    refine_subpixel: bool = field(
        default=False,
        metadata={
            'help': 'refine detected corners in the raw image with cornerSubPix (worse on MATRIX: rows 3-6 px apart)'
        },
    )
    track_corners: bool = field(
        default=False,
        metadata={
            'help': 'after a searched good frame, first try the board corners predicted by the previous pose and the '
            'ORB ground homography (refined and verified as by grow_corners) and skip the checkerboard search '
            'when they give a plausible pose. Measured (bench_calib.py, 1080p): calib 2-3x faster and more '
            'frames ok, but a worse worst case on grazing boards (simulated modified 0.52 deg against 0.12): '
            'off by default'
        },
    )
    track_max_frames: int = field(
        default=2,
        metadata={
            'help': 'after this many tracked frames in a row the next one is searched: tracked poses drift (simulated '
            'complex, worst rotation: 0.19 deg with 2, 0.40 with 4, 0.70 unlimited; searched only 0.12)'
        },
    )
    track_matcher: str = field(
        default='lsh',
        metadata={
            'help': 'motion_matcher of the frames that try track_corners first (a frame that then needs the search '
            'measures its homography again with motion_matcher)'
        },
    )
    track_registered: bool = field(
        default=True,
        metadata={
            'help': 'when the frame comes with its registration (the calib node with use_registration), first try '
            'the board corners the camera it implies predicts, refined and verified as with track_corners, and '
            'skip the search when they give a plausible pose. That prior does not drift (every frame is '
            'registered to the same reference): measured (bench_drone.py --registration-prior), every real '
            'and simulated frame ok, worst 0.07 deg real, 0.15 / 0.21 deg simulated complex / modified'
        },
    )
    track_start_move: float = field(
        default=0.3,
        metadata={
            'help': 'tracking (track_registered, track_corners): when the predicted corners verify too few saddles, '
            'a second try whose first refinement accepts a corner that moved up to this many squares (the '
            'first try and the rounds from solved poses: 0.15). '
            'A tracked registration guides to about 0.05 deg, 1-2 px on boards whose rows are 3-6 px high: '
            'with 0.15 real D7 frame 4 verified 5 of 351 corners and was lost, with 0.3 all 351'
        },
    )
    registration_agreement_m: float = field(
        default=0.3,
        metadata={
            'help': "a pose whose camera centre is further than this from the one the frame's registration implies is "
            'rejected (stale): two independent estimates disagree (measured: registrations within 3 cm, '
            'searched poses that misnamed a piece 0.7 m off)'
        },
    )
    grow_corners: bool = field(
        default=True,
        metadata={'help': 'after a first pose, refine and verify every predicted board corner and solve again'},
    )
    full_search: bool = field(
        default=True, metadata={'help': 'search the whole image when the rectified views found nothing'}
    )
    full_search_scale: float = field(
        default=0.5,
        metadata={
            'help': 'image scale of that whole-image search (its pieces only seed the pose: grow refines every '
            'corner at full resolution); measured on the real sample: 1.5 s at 0.5 against 5 s at 1.0, the '
            'same views recovered; boards whose squares get too small at that scale are missed (1.0 = full)'
        },
    )
    ambiguity_ratio: float = field(
        default=0.95,
        metadata={
            'help': 'a corner assignment scoring at least this fraction of the best one (checker-colour '
            'evidence) is a rival; rivals the prior cannot separate make the piece ambiguous (rejected)'
        },
    )
    max_index_error: float = field(
        default=2.5,
        metadata={'help': 'assignments further than this many squares from the prior prediction are not considered'},
    )
    index_separation: float = field(
        default=0.6,
        metadata={
            'help': 'the prior separates two rival assignments when one is closer to its prediction by this '
            'many squares'
        },
    )
    max_prior_rotation_deg: float = field(
        default=35.0,
        metadata={'help': 'orientation hypotheses whose rotation differs from the prior by more than this are dropped'},
    )
    pnp_ransac_px: float = field(default=2.0, metadata={'help': 'PnP RANSAC inlier threshold, pixels'})
    max_reprojection_px: float = field(
        default=0.8, metadata={'help': 'a pose whose RMS reprojection error exceeds this is rejected (status stale)'}
    )
    min_corners: int = field(default=12, metadata={'help': 'fewer inlier corners than this -> stale'})
    max_jump_m: float = field(
        default=2.0,
        metadata={'help': 'a camera centre further than this from the previous good one is an implausible jump'},
    )
    max_jump_deg: float = field(
        default=25.0,
        metadata={'help': 'a rotation further than this from the previous good one is an implausible jump'},
    )
    initial_prior_jump_m: float = field(
        default=8.0,
        metadata={'help': 'jump limit while the prior is still the configured/reference pose (it can be metres off)'},
    )
    initial_prior_jump_deg: float = field(
        default=45.0, metadata={'help': 'rotation jump limit while the prior is still the configured/reference pose'}
    )
    calib_seed: int = field(
        default=0,
        metadata={
            'help': "seed of OpenCV's RNG (the RANSAC steps), set before every image: reproducible results, the "
            'same whether drones share a process or not'
        },
    )

    def check(self) -> None:
        if self.pattern_size < 3:
            raise ValueError('pattern_size must be >= 3')
        if self.px_per_square < 3 or self.margin_cells < 0 or self.initial_margin_cells < 0:
            raise ValueError('px_per_square must be >= 3, margin_cells and initial_margin_cells >= 0')
        if not 0 < self.full_search_scale <= 1:
            raise ValueError('full_search_scale must be in (0, 1]')
        if self.track_max_frames < 1:
            raise ValueError('track_max_frames must be >= 1')
        if self.motion_features < 100:
            raise ValueError('motion_features must be >= 100')
        for name in ('motion_matcher', 'track_matcher'):
            if getattr(self, name) not in ('lsh', 'brute'):
                raise ValueError(f'{name} must be lsh or brute, got {getattr(self, name)!r}')
        if not 0 <= self.global_shift_scale <= 1:
            raise ValueError('global_shift_scale must be in [0, 1]')
        if not 0.15 <= self.track_start_move < 0.5:
            raise ValueError('track_start_move must be in [0.15, 0.5) squares (half a square reaches the next corner)')
        if not 0 < self.ambiguity_ratio < 1:
            raise ValueError('ambiguity_ratio must be in (0, 1)')
        for name in (
            'registration_agreement_m',
            'pnp_ransac_px',
            'max_reprojection_px',
            'max_jump_m',
            'max_jump_deg',
            'initial_prior_jump_m',
            'initial_prior_jump_deg',
            'max_prior_rotation_deg',
        ):
            if getattr(self, name) <= 0:
                raise ValueError(f'{name} must be positive')
        if self.min_corners < 6 or self.max_pieces_per_board < 1:
            raise ValueError('min_corners must be >= 6 and max_pieces_per_board >= 1')
