"""``matrix-tracker site check SITE``: load and validate a site file (docs/site-file.md) and summarise it.

A bad file is one line naming the file, the key and the fault, exit status 2. Missing reference files are
listed (exit 0) unless ``--require-references``, which makes them an error as for a command that reads them.
"""

from matrix_core.site.load import load_site
from matrix_core.site.shipped import shipped_sites, site_path
from matrix_core.site.summary import format_site


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'site', help='site files: check one (area, drones, boards, references)', description=__doc__
    )
    actions = p.add_subparsers(dest='site_command', metavar='ACTION', required=True)
    check = actions.add_parser('check', help='validate a site file and print its summary', description=__doc__)
    check.add_argument('site', help=f'site file, or the name of a shipped one ({", ".join(shipped_sites())})')
    check.add_argument(
        '--require-references',
        action='store_true',
        help='fail (exit 2) unless every drone\'s reference image and calibration can be read',
    )
    check.set_defaults(func=run_check)
    init = actions.add_parser(
        'init',
        help='write a site file, reference images and calibrations from a recording and its boards',
        description=init_doc(),
    )
    source = init.add_mutually_exclusive_group(required=True)
    source.add_argument('--bag', help='rosbag2 of the drones: <drone>/image_raw or image/compressed + camera_info')
    source.add_argument('--images', help='folder of images per drone (<drone>/*.png|jpg); intrinsics from --intrinsics')
    init.add_argument(
        '--boards',
        required=True,
        help='YAML: area, boards (site file format), optional name, cell_m, obstacles, priors; or a site file',
    )
    init.add_argument(
        '--intrinsics',
        help='with --images: YAML drone -> {image_size, K, dist} (default: the cameras of a --boards site file)',
    )
    init.add_argument('--frames', type=int, default=5, help='frames per drone considered, spread over the recording')
    init.add_argument('--out', required=True, help='new folder for site.yaml and references/ (must be new or empty)')
    init.set_defaults(func=run_init)


def run_check(args) -> int:
    site = load_site(site_path(args.site), require_references=args.require_references)
    text, _ = format_site(site)
    print(text)
    return 0


def init_doc() -> str:
    from matrix_core.site import init

    return init.__doc__


def run_init(args) -> int:
    """Calibrate each drone's best frame, print each drone's outcome, write the drones that have one."""
    from matrix_core.output_paths import check_output
    from matrix_core.settings import read_yaml
    from matrix_core.site.init import calibrate_drone, frames_from_bag, frames_from_folder, read_boards, write_site
    from matrix_core.site.load import SiteError

    if args.frames < 1:
        raise SiteError(f'--frames must be >= 1, got {args.frames}')
    recording = args.bag or args.images
    check_output(args.out, [recording, args.boards, args.intrinsics])  # before any work
    draft = read_boards(args.boards)
    if args.bag:
        frames = frames_from_bag(args.bag, args.frames)
    else:
        intrinsics = (
            read_yaml(args.intrinsics) if args.intrinsics else {n: d['camera'] for n, d in draft.drones.items()}
        )
        frames = frames_from_folder(args.images, intrinsics, args.frames)
    if not frames:
        raise SiteError(f'{recording}: no drone with images (and camera_info) found')
    written, left_out = [], []
    for drone, drone_frames in frames.items():
        ref = calibrate_drone(drone, drone_frames, draft.boards, draft.priors.get(drone))
        if ref.camera is None:
            left_out.append(ref)
            print(f'{drone}: left out: {ref.reason}')
        else:
            written.append(ref)
            print(
                f'{drone}: reference frame {ref.frame} of {len(drone_frames.images)}'
                + (f' (t={ref.stamp_s:.3f} s)' if ref.stamp_s is not None else '')
                + f', {ref.corners} board corners, '
                f'reprojection {ref.rms_px:.2f} px rms (prior: {ref.prior})'
            )
    if not written:
        raise SiteError(f'{recording}: no drone saw a board; nothing written')
    path = write_site(args.out, draft, written)
    print(
        f'wrote {path}: {len(written)} drone(s)'
        + (f'; left out: {", ".join(r.drone for r in left_out)}' if left_out else '')
    )
    return 0
