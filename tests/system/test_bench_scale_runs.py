"""``scripts/bench_scale.py`` runs end to end on a tiny configuration (2 and 4 drones, 10 people, 15 m, one timed
frame, 5 tracker frames): it renders the sites, measures every stage in its worker and writes its table, figure
and JSON with sane values. The figures themselves are the benchmark's (docs/scaling.md), not checked."""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STAGES = ('decode', 'register', 'calib', 'network', 'lifting', 'tracker', 'messages')


def test_bench_scale_tiny_run_writes_table_and_figure(tmp_path):
    run = subprocess.run(
        [
            sys.executable,
            str(ROOT / 'scripts/bench_scale.py'),
            '--drones',
            '2',
            '4',
            '--people',
            '10',
            '--sides',
            '15',
            '--base',
            '2',
            '10',
            '15',
            '--frames',
            '1',
            '--tracker_frames',
            '5',
            '--out',
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-3000:]
    table = (tmp_path / 'scale.md').read_text()
    assert table in run.stdout
    assert '| sweep | drones | people | side m | decode |' in table and '| total |' in table
    assert 'tracker <= 2 ms per frame at 200 people' in table
    png = (tmp_path / 'scale.png').read_bytes()
    assert png[:8] == b'\x89PNG\r\n\x1a\n' and len(png) > 10_000
    results = json.loads((tmp_path / 'scale.json').read_text())['results']
    assert sorted(r['drones'] for r in results) == [2, 4]
    for r in results:
        assert all(r['cpu_ms'][s] >= 0 for s in STAGES) and r['cpu_ms']['network'] > 0 and r['cpu_ms']['register'] > 0
        assert r['images'] >= r['drones'] * 2 and r['rss_peak_mb'] > r['rss_setup_mb'] * 0.5 > 0
    two, four = sorted(results, key=lambda r: r['drones'])
    assert four['cpu_ms']['decode'] > two['cpu_ms']['decode']  # twice the images
