"""The small, committable part of a run: ``run.json``, every step's ``steps/<name>.done.json`` (params,
wall time, commit), every ``metrics.json`` and the trajectory PNGs, copied to a metrics folder
(``docs/results/<size>/`` for docs/RESULTS.md). The report is written from that folder, so
``matrix-tracker experiments --report-only`` regenerates RESULTS.md from the committed files alone and
anyone can audit each number against the step that produced it."""

import shutil
from pathlib import Path

# Relative glob patterns of the files kept (everything else of a run is large or reproducible).
KEPT = (
    'run.json',
    'steps/**/*.done.json',
    'steps/**/*.error.txt',
    'eval/*/metrics.json',
    'eval/*/trajectories.png',
    'tables/*/metrics.json',
)


def archive_run(run_dir, dest) -> Path:
    """Replace ``dest`` with the kept files of ``run_dir`` (same relative layout); returns ``dest``."""
    run_dir, dest = Path(run_dir), Path(dest)
    if not (run_dir / 'run.json').is_file():
        raise FileNotFoundError(f'{run_dir / "run.json"} is missing: run `matrix-tracker experiments` first')
    if dest.resolve() == run_dir.resolve():
        return dest
    if dest.exists():
        shutil.rmtree(dest)
    for pattern in KEPT:
        for src in sorted(run_dir.glob(pattern)):
            target = dest / src.relative_to(run_dir)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, target)
    return dest


def default_metrics_dir(report, size_name: str) -> Path:
    """``<report folder>/results/<size>`` (docs/results/standard for docs/RESULTS.md)."""
    return Path(report).parent / 'results' / size_name
