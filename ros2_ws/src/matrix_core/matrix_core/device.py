"""Where the network runs: the ``device`` setting (``auto`` | ``cpu`` | ``cuda`` | ``cuda:N``) of the fuse node,
``matrix-tracker evaluate``, ``train`` and ``experiments``, and the one function that turns it into a
``torch.device``.

``auto`` is the first CUDA GPU when PyTorch sees one, else the CPU, and says which in the log; a GPU named
explicitly that this machine lacks is an error (:class:`DeviceError`, a ValueError) raised when the settings
are built, before any work starts: nothing falls back to the CPU silently. torch is imported only when a GPU
is named or ``auto`` is resolved, so that settings stay cheap to build.
"""

import re
import sys
from dataclasses import dataclass, field

from matrix_core.settings import Settings

DEVICE_CHOICES = ('auto', 'cpu', 'cuda', 'cuda:N')
DEFAULT_DEVICE = 'auto'
_CUDA = re.compile(r'cuda(?::(\d+))?')


class DeviceError(ValueError):
    """A device setting that names no device of this machine, or no device at all."""


@dataclass
class DeviceSettings(Settings):
    """The device of the BEV network (its encoder, lifting, aggregation, heads and peak finding)."""

    device: str = field(
        default=DEFAULT_DEVICE,
        metadata={
            'help': 'where the BEV network runs: auto (the first CUDA GPU when there is one, else the CPU; the log '
            'says which), cpu, cuda or cuda:N; a GPU this machine lacks is an error at start'
        },
    )

    def check(self) -> None:
        check_device(self.device)


def _cuda_index(spec: str):
    """N of 'cuda:N' (0 for 'cuda'), None when ``spec`` is no CUDA device name."""
    match = _CUDA.fullmatch(spec)
    if match is None:
        return None
    return int(match.group(1) or 0)


def check_device(spec: str) -> None:
    """:class:`DeviceError` unless ``spec`` is one of :data:`DEVICE_CHOICES` and, for a GPU, one this machine has."""
    if not isinstance(spec, str) or (spec not in ('auto', 'cpu') and _cuda_index(spec) is None):
        raise DeviceError(f'device {spec!r} is not one of {", ".join(DEVICE_CHOICES)}')
    index = _cuda_index(spec)
    if index is None:
        return
    import torch

    if not torch.cuda.is_available():
        raise DeviceError(
            f'device {spec!r}: this machine has no CUDA device (PyTorch {torch.__version__} sees none); '
            "use device 'cpu' or 'auto'"
        )
    count = torch.cuda.device_count()
    if index >= count:
        raise DeviceError(
            f'device {spec!r}: no CUDA device {index}; this machine has {count} (cuda:0 to cuda:{count - 1})'
        )


def _stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def resolve_device(spec: str, log=_stderr):
    """The ``torch.device`` a device setting names (errors as :func:`check_device`). ``auto`` tells ``log`` what it
    chose, e.g. 'device: auto chose cpu (no CUDA device)' (default: standard error, so that a command's output
    stays its own). On a GPU, float32 convolutions and matrix products are kept in full float32 (TF32 off), so that
    its outputs equal the CPU's to float rounding (heatmap logits within 1e-3, tests/bev/test_device.py)."""
    import torch

    check_device(spec)
    if spec == 'auto':
        if torch.cuda.is_available():
            device = torch.device('cuda', 0)
            log(f'device: auto chose {device} ({torch.cuda.get_device_name(0)})')
        else:
            device = torch.device('cpu')
            log('device: auto chose cpu (no CUDA device)')
    else:
        device = torch.device(spec if spec == 'cpu' else f'cuda:{_cuda_index(spec)}')
    if device.type == 'cuda':
        torch.backends.cudnn.allow_tf32 = False
        torch.backends.cuda.matmul.allow_tf32 = False
    return device


def model_device(model):
    """The device of a module's parameters (the CPU for one without parameters)."""
    import torch

    return next((p.device for p in model.parameters()), torch.device('cpu'))
