"""Offline weights of the kornia backends: where kornia looks for them and a clear error when absent.

kornia loads pretrained weights from the torch hub cache, ``torch.hub.get_dir()/checkpoints/<name>``,
and would otherwise try to download them (impossible on our machines). We check first and say exactly
which file is missing and where to put it, instead of waiting for kornia's download retries.
"""

from pathlib import Path

HARDNET_FILE = 'checkpoint_liberty_with_aug.pth'
HARDNET_URLS = (
    'https://huggingface.co/kornia/hardnet/resolve/main/checkpoint_liberty_with_aug.pth',
    'https://github.com/DagnyT/hardnet/raw/master/pretrained/train_liberty_with_aug/checkpoint_liberty_with_aug.pth',
)
AFFNET_FILE = 'AffNet.pth'
HARDTFEAT_FILE = 'HardTFeat.pth'


class MissingWeightsError(FileNotFoundError):
    """A pretrained weight file is not in the torch hub cache (the message names the file and folder)."""


def checkpoint_dir() -> Path:
    """The folder kornia reads cached weights from: ``torch.hub.get_dir()/checkpoints``."""
    import torch

    return Path(torch.hub.get_dir()) / 'checkpoints'


def require_checkpoint(name: str, what: str, source: str = '') -> Path:
    """Path of cached weight file ``name``; raises :class:`MissingWeightsError` saying where to put it."""
    path = checkpoint_dir() / name
    if not path.is_file():
        hint = f' It comes from {source}.' if source else ''
        raise MissingWeightsError(
            f'{what} needs the weight file {name}, which is missing: put it at {path} '
            f'(the torch hub checkpoints folder, torch.hub.get_dir()/checkpoints/; `make setup` links the '
            f'offline copies from shared/weights there).{hint}'
        )
    return path


def require_hardnet() -> Path:
    """HardNet's weights (not available offline here; see shared/weights/README.md)."""
    return require_checkpoint(
        HARDNET_FILE,
        'The gftt_affnet_hardnet backend (kornia HardNet descriptor)',
        ' or '.join(HARDNET_URLS) + '; until then use gftt_affnet_hardtfeat or gftt_affnet_sift, which are '
        'substitutes, not HardNet',
    )


def load_hardtfeat():
    """kornia ``TFeat`` holding the HardTFeat weights (TFeat architecture trained with the HardNet loss).

    The file's keys are renamed to kornia's layout (see shared/weights/README.md). Its output is not
    L2-normalised: the backend normalises.
    """
    import torch
    import kornia.feature as KF

    path = require_checkpoint(
        HARDTFEAT_FILE, 'The gftt_affnet_hardtfeat backend', 'shared/weights/extra/HardTFeat.pth (ducha-aiki/affnet)'
    )
    sd = torch.load(path, map_location='cpu', weights_only=True)['state_dict']
    model = KF.TFeat(pretrained=False)
    model.load_state_dict(
        {
            'features.1.weight': sd['features.0.weight'],
            'features.1.bias': sd['features.0.bias'],
            'features.4.weight': sd['features.3.weight'],
            'features.4.bias': sd['features.3.bias'],
            'descr.0.weight': sd['classifier.1.weight'].reshape(128, -1),
            'descr.0.bias': sd['classifier.1.bias'],
        }
    )
    return model.eval()
