"""A training config small enough for a test: the real sample's frames 0-2 to train, 3-4 to validate, the tiny
model at 160x96 input and 0.5 m cells. Importable as ``tiny_training`` (the root conftest.py puts this folder
on the path)."""


def tiny_config(folder, matrix_sample, monkeypatch, extra: str):
    """Write ``folder/tiny.yaml`` (the sample found through ``$MATRIX_SHARED``, set with ``monkeypatch``) with the
    YAML lines ``extra`` (epochs, seed, ...) appended; returns its path."""
    monkeypatch.setenv('MATRIX_SHARED', str(matrix_sample.parent))
    cfg = folder / 'tiny.yaml'
    cfg.write_text(f"""
train:
  - path: $MATRIX_SHARED/{matrix_sample.name}
    frames: [0, 2]
val:
  - path: $MATRIX_SHARED/{matrix_sample.name}
    frames: [3, 4]
bev: {{model: bev_tiny, image_width: 160, image_height: 96, cell_m: 0.5}}
{extra}""")
    return cfg
