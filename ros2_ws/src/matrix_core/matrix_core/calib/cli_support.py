"""Simulated MATRIX sequences for the calibration's tests and benchmark (through the public CLI)."""

from pathlib import Path

from matrix_core.cli.main import main as cli_main


def simulated_sequence(variant: str, frames: int, seed: int, out) -> Path:
    """Write ``frames`` frames of simulator ``variant`` to ``out`` (MATRIX format) and return ``out``."""
    out = Path(out)
    code = cli_main(['simulate', '--config', variant, '--frames', str(frames), '--seed', str(seed),
                     '--out', str(out)])
    if code != 0:
        raise RuntimeError(f'matrix-tracker simulate {variant} failed with exit code {code}')
    return out
