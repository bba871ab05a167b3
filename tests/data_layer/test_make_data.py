"""`make data` (scripts/data.sh, scripts/data_manifest.py): the real shared folder passes, an empty one fails
fast with the instructions, and the checksum manifest catches a modified file."""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DATA_SH = ROOT / 'scripts' / 'data.sh'
MANIFEST_PY = ROOT / 'scripts' / 'data_manifest.py'
MANIFEST = ROOT / 'scripts' / 'matrix_sample.sha256'


def run_data(shared: Path, *args, **env) -> subprocess.CompletedProcess:
    return subprocess.run(
        ['bash', str(DATA_SH), *args],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, 'MATRIX_SHARED': str(shared), **env},
    )


def test_the_real_shared_folder_passes(shared_dir):
    r = run_data(shared_dir)
    assert r.returncode == 0, r.stdout + r.stderr
    for folder in ('matrix_sample', 'multiviewx_sample', 'weights', 'ros2_cli'):
        assert f'found    {folder}/' in r.stdout
    assert 'checksums ok' in r.stdout and 'data: ready' in r.stdout
    assert run_data(shared_dir, '--require', 'matrix_sample,multiviewx_sample').returncode == 0


def test_an_empty_folder_fails_fast_with_the_instructions(tmp_path):
    # an unreachable repository (no network here either way): the download is tried, bounded, and refused
    start = time.monotonic()
    r = run_data(tmp_path, MATRIX_REPO_URL=str(tmp_path / 'no_such_repo'), MATRIX_NET_TIMEOUT='5')
    assert time.monotonic() - start < 30
    assert r.returncode != 0
    assert 'download impossible' in r.stderr
    assert f'{tmp_path}/matrix_sample/' in r.stderr and 'Put the data here' in r.stderr
    assert not (tmp_path / 'matrix_sample').exists()
    # make test / make demo: the same message, no download attempted
    r = run_data(tmp_path, '--require', 'matrix_sample')
    assert r.returncode != 0 and 'missing: matrix_sample' in r.stderr and 'trying' not in r.stdout


def test_the_default_repository_attempt_is_bounded(tmp_path):
    start = time.monotonic()
    r = run_data(tmp_path, MATRIX_NET_TIMEOUT='5')
    assert time.monotonic() - start < 60
    assert r.returncode != 0 and 'Put the data here' in r.stderr


def _copy_of_a_few_files(matrix_sample: Path, to: Path) -> list:
    """A copy of the manifest's entries under annotations_positions/ and calibrations/intrinsic/, and a
    manifest of just those; returns their relative paths."""
    lines = [
        line
        for line in MANIFEST.read_text().splitlines()
        if line.split()[2].startswith(('annotations_positions/', 'calibrations/intrinsic/intr_Drone1_'))
    ]
    rels = [line.split()[2] for line in lines]
    for rel in rels:
        (to / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(matrix_sample / rel, to / rel)
    (to / 'manifest').write_text('\n'.join(lines) + '\n')
    return rels


def check(folder: Path, manifest: Path, *extra) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(MANIFEST_PY), 'check', str(folder), str(manifest), *extra],
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_the_manifest_detects_a_modified_or_missing_file(matrix_sample, tmp_path):
    copy = tmp_path / 'sample'
    rels = _copy_of_a_few_files(matrix_sample, copy)
    assert len(rels) >= 10
    assert check(copy, copy / 'manifest').returncode == 0
    victim = copy / 'annotations_positions' / '0002.json'
    victim.write_bytes(victim.read_bytes().replace(b'1', b'2', 1))
    r = check(copy, copy / 'manifest')
    assert r.returncode == 1 and 'checksum differs: annotations_positions/0002.json' in r.stderr
    (copy / rels[-1]).unlink()
    r = check(copy, copy / 'manifest', '--upstream')
    assert r.returncode == 1 and f'missing: {rels[-1]}' in r.stderr


def test_the_manifest_covers_the_whole_sample_and_its_matchings_folders():
    kinds = {}
    for line in MANIFEST.read_text().splitlines():
        digest, kind, rel = line.split(None, 2)
        assert len(digest) == 64
        kinds.setdefault(kind, []).append(rel)
    assert len(kinds['image']) == 48 and all(r.endswith('.jpg') for r in kinds['image'])  # 40 + 8 reference
    assert sorted(kinds['tree']) == ['matchings/Pedestrians', 'matchings/Pedestrians/LoS', 'matchings/Planes']
    assert kinds['local'] == ['README.md']
