#!/usr/bin/env python3
"""Checksums of the MATRIX sample (stdlib only: it runs before `make setup`).

The manifest (scripts/matrix_sample.sha256) has one line per entry, ``SHA256  KIND  PATH``:
  file   a file byte-identical to the public MATRIX repository's sample (text, JSON, XML);
  image  a JPEG of ours (the repository has the same name with .png: only its presence is checked there);
  local  a file only our copy has (its README);
  tree   a folder of many small files (matchings/...), hashed as the sha256 of its sorted ``sha256  name``
         lines, so the manifest stays small; a changed file names its folder.

    python scripts/data_manifest.py write ../shared/matrix_sample scripts/matrix_sample.sha256
    python scripts/data_manifest.py check ../shared/matrix_sample scripts/matrix_sample.sha256
    python scripts/data_manifest.py check DOWNLOADED scripts/matrix_sample.sha256 --upstream
"""

import argparse
import hashlib
import sys
from pathlib import Path

TREES = ('matchings/Planes', 'matchings/Pedestrians', 'matchings/Pedestrians/LoS')
LOCAL = ('README.md',)


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open('rb') as f:
        for block in iter(lambda: f.read(1 << 20), b''):
            h.update(block)
    return h.hexdigest()


def tree_sha256(folder: Path) -> str:
    """sha256 of the sorted ``sha256  name`` lines of the files directly in a folder."""
    lines = sorted(f'{sha256(p)}  {p.name}\n' for p in folder.iterdir() if p.is_file())
    return hashlib.sha256(''.join(lines).encode()).hexdigest()


def entries(root: Path) -> list:
    """[(sha256, kind, relative path)] of a sample folder, sorted by path."""
    out = [(tree_sha256(root / t), 'tree', t) for t in TREES]
    for p in sorted(root.rglob('*')):
        rel = p.relative_to(root).as_posix()
        if not p.is_file() or str(Path(rel).parent) in TREES:
            continue
        kind = 'local' if rel in LOCAL else 'image' if p.suffix == '.jpg' else 'file'
        out.append((sha256(p), kind, rel))
    return sorted(out, key=lambda e: e[2])


def read_manifest(path: Path) -> list:
    return [tuple(line.split(None, 2)) for line in path.read_text().splitlines() if line.strip()]


def check(root: Path, manifest: Path, upstream: bool) -> list:
    """Problems (strings) of a sample folder against the manifest; [] when it matches.
    upstream: a copy from the public repository (images are .png there, our README absent)."""
    problems = []
    for digest, kind, rel in read_manifest(manifest):
        path = root / rel
        if upstream and kind == 'local':
            continue
        if upstream and kind == 'image':
            if not (path.is_file() or path.with_suffix('.png').is_file()):
                problems.append(f'missing: {rel} (or .png)')
            continue
        if not (path.is_dir() if kind == 'tree' else path.is_file()):
            problems.append(f'missing: {rel}')
        elif (tree_sha256(path) if kind == 'tree' else sha256(path)) != digest:
            problems.append(f'checksum differs: {rel}' + (' (a file in this folder)' if kind == 'tree' else ''))
    return problems


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('action', choices=('write', 'check'))
    p.add_argument('folder', type=Path)
    p.add_argument('manifest', type=Path)
    p.add_argument('--upstream', action='store_true', help='a copy from the public repository (PNG images)')
    args = p.parse_args()
    if args.action == 'write':
        lines = [f'{d}  {k}  {r}\n' for d, k, r in entries(args.folder)]
        args.manifest.write_text(''.join(lines))
        print(f'{args.manifest}: {len(lines)} entries')
        return 0
    problems = check(args.folder, args.manifest, args.upstream)
    for line in problems[:20]:
        print(f'  {line}', file=sys.stderr)
    if len(problems) > 20:
        print(f'  ... and {len(problems) - 20} more', file=sys.stderr)
    return 1 if problems else 0


if __name__ == '__main__':
    sys.exit(main())
