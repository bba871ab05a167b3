"""``matrix-tracker site check``: a summary of a good site, one line naming file and key for a bad one."""

import re
import subprocess
import sys
from pathlib import Path

import yaml

from matrix_core.cli.main import main
from matrix_core.site.shipped import SITES_DIR


def test_check_prints_the_plaza_summary(capsys):
    assert main(['site', 'check', 'plaza']) == 0
    out = capsys.readouterr().out
    assert 'area: x -24..24 m, y -12..12 m (48 x 24 m)' in out
    assert 'grid 96 x 192 cells' in out
    assert 'drones: 5' in out and '  alpha: 1280x720 px' in out and 'altitude 18 m' in out
    assert 'boards: 3' in out and '  north: 16 x 12 squares of 0.3 m' in out
    assert 'kiosk: x 6..10 m, y -6..-2 m, 4 m high' in out
    assert 'references: to be simulated' in out


def test_check_lists_the_matrix_references_found_and_missing(capsys, monkeypatch, matrix_sample, tmp_path):
    monkeypatch.setenv('MATRIX_SHARED', str(matrix_sample.parent))
    assert main(['site', 'check', str(SITES_DIR / 'matrix.yaml'), '--require-references']) == 0
    out = capsys.readouterr().out
    assert out.count(': found') == 8 and 'reference camera at 12.29 m' in out
    monkeypatch.setenv('MATRIX_SHARED', str(tmp_path))  # no matrix_sample there
    assert main(['site', 'check', 'matrix']) == 0
    out = capsys.readouterr().out
    assert out.count(': missing ') == 8
    assert main(['site', 'check', 'matrix', '--require-references']) == 2
    err = capsys.readouterr().err
    assert 'matrix.yaml: drones[0] (D1).reference: no such file' in err


def test_bad_file_is_one_line_and_exit_2(tmp_path):
    data = yaml.safe_load((SITES_DIR / 'plaza.yaml').read_text())
    data['drones'][3]['camera'] = dict(data['drones'][3]['camera'], size=[1, 1])
    path = tmp_path / 'bad.yaml'
    path.write_text(yaml.safe_dump(data))
    cmd = [sys.executable, '-m', 'matrix_core.cli.main', 'site', 'check', str(path)]
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 2
    assert result.stdout == ''
    assert result.stderr.strip().splitlines() == [
        f"matrix-tracker site: error: {path.resolve()}: drones[3] (delta).camera: unknown key 'size' "
        '(allowed: K, dist, image_size)'
    ]


def test_no_such_site_names_the_shipped_ones(capsys):
    assert main(['site', 'check', 'nowhere']) == 2
    err = capsys.readouterr().err
    assert 'site file not found: nowhere (a path, or a shipped site: matrix, plaza, ring12, ring3)' in err


def test_the_docs_example_is_the_shipped_plaza():
    page = (Path(__file__).resolve().parents[2] / 'docs' / 'site-file.md').read_text()
    section = page.split('## The format, with the plaza as the example', 1)[1]
    example = re.search(r'```yaml\n(.*?)```', section, flags=re.S).group(1)
    assert yaml.safe_load(example) == yaml.safe_load((SITES_DIR / 'plaza.yaml').read_text())
