"""Where the core finds what lives outside its own package, each in one named way (never by counting parent
folders of a source file, which breaks once the package is installed elsewhere):

- the shared data folder (the real samples, the ROS 2 interface and CLI sources): ``$MATRIX_SHARED``, which
  ``scripts/env.sh`` sets (to ``shared`` beside the checkout unless already set);
- a file a package of the workspace installs under ``share/<package>/`` (matrix_calib's calibration scenes):
  looked up on ``$AMENT_PREFIX_PATH`` as ``ament_index_python`` does (the built workspace is on it once
  ``scripts/env.sh`` is sourced);
- the git checkout this code runs from (the provenance of experiment results): git's own answer for the folder
  of this file.
"""

import os
import subprocess
from pathlib import Path

SHARED_VARIABLE = 'MATRIX_SHARED'


def shared_dir() -> Path:
    """The shared data folder, ``$MATRIX_SHARED`` (FileNotFoundError saying how to set it when unset; a caller
    that needs something in it says when that is missing)."""
    value = os.environ.get(SHARED_VARIABLE, '')
    if not value:
        raise FileNotFoundError(
            f'${SHARED_VARIABLE} is not set: source scripts/env.sh (it points it at ../shared beside the checkout) '
            f'or export {SHARED_VARIABLE}=<the shared data folder>'
        )
    return Path(value)


def package_share(package: str, *parts: str) -> Path:
    """``share/<package>/<parts>`` of the first prefix on ``$AMENT_PREFIX_PATH`` that has it, e.g.
    ``package_share('matrix_calib', 'config', 'matrix_sample.yaml')``; FileNotFoundError naming where it looked."""
    prefixes = [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    for prefix in prefixes:
        path = Path(prefix, 'share', package, *parts)
        if path.exists():
            return path
    raise FileNotFoundError(
        f'{Path(package, *parts)} is in no share/ folder of $AMENT_PREFIX_PATH ({prefixes or "unset"}): build the '
        'workspace (make build) and source scripts/env.sh'
    )


def code_checkout() -> Path:
    """The top folder of the git checkout holding this code; None when it is not in one (an installed copy)."""
    try:
        top = subprocess.run(
            ['git', '-C', str(Path(__file__).resolve().parent), 'rev-parse', '--show-toplevel'],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return Path(top) if top else None
