"""kornia GFTT + AffNet (+ LAFOrienter) detector with a choice of patch descriptor.

The detector is exactly kornia's ``GFTTAffNetHardNet`` detector (ScaleSpaceDetector with CornerGFTT,
AffNet affine shape, LAFOrienter(19)). Descriptors:

- ``hardnet``: kornia HardNet, the paper's method; needs ``checkpoint_liberty_with_aug.pth`` (missing
  offline here: :func:`~matrix_core.register.weights.require_hardnet` says so clearly);
- ``hardtfeat``: TFeat architecture trained with the HardNet loss (a substitute, NOT HardNet);
- ``sift``: kornia's SIFTDescriptor (RootSIFT) on the AffNet patches (a substitute, no weights).
"""

import numpy as np

from matrix_core.register.features import Features, mask_at, resize, to_full_resolution, to_gray
from matrix_core.register.weights import AFFNET_FILE, load_hardtfeat, require_checkpoint, require_hardnet


def _patch_descriptor(kind: str):
    """(B, 1, 32, 32) patches -> (B, D) L2-normalised descriptors, as a torch module."""
    import torch
    import kornia.feature as KF

    if kind == 'hardnet':
        require_hardnet()
        return KF.HardNet(pretrained=True).eval()
    if kind == 'hardtfeat':
        tfeat = load_hardtfeat()

        class _Normalised(torch.nn.Module):
            def forward(self, patches):
                return torch.nn.functional.normalize(tfeat(patches), dim=1)

        return _Normalised().eval()
    if kind == 'sift':
        return KF.SIFTDescriptor(32, rootsift=True).eval()
    raise ValueError(f'unknown kornia descriptor {kind!r}')


class GfttAffNetBackend:
    """kornia GFTT-AffNet features at ``scale`` of the input resolution with descriptor ``descriptor``.

    Slow on a CPU (seconds per image even at 480x270): an accuracy reference, not the real-time default.
    torch is limited to one thread (the machines are shared).
    """

    def __init__(self, descriptor: str, scale: float = 0.25):
        import torch
        import kornia.feature as KF

        torch.set_num_threads(1)
        require_checkpoint(
            AFFNET_FILE, f'The gftt_affnet_{descriptor} backend (AffNet affine shape)', 'shared/weights/AffNet.pth'
        )
        self.name = f'gftt_affnet_{descriptor}'
        self.scale = scale
        self._descriptor = KF.LAFDescriptor(_patch_descriptor(descriptor), patch_size=32, grayscale_descriptor=True)
        self._kf = KF
        self._detectors = {}

    def _detector(self, num_features: int):
        """kornia's GFTTAffNetHardNet detector, cached per feature budget."""
        if num_features not in self._detectors:
            from kornia.geometry.transform import ScalePyramid

            KF = self._kf
            self._detectors[num_features] = KF.ScaleSpaceDetector(
                num_features,
                resp_module=KF.CornerGFTT(),
                scale_pyr_module=ScalePyramid(3, 1.6, 32, double_image=True, extra_levels=2),
                ori_module=KF.LAFOrienter(19),
                aff_module=KF.LAFAffNetShapeEstimator(True, preserve_orientation=False).eval(),
                scale_space_response=False,
                minima_are_also_good=False,
                mr_size=6.0,
            ).eval()
        return self._detectors[num_features]

    def extract(self, image: np.ndarray, max_features: int, mask: np.ndarray = None) -> Features:
        """See :class:`~matrix_core.register.features.FeatureBackend`; ``mask`` only drops the features
        outside it (the detector still runs on the whole image)."""
        import torch

        gray = resize(to_gray(image), self.scale)
        timg = torch.from_numpy(gray).float()[None, None] / 255.0
        with torch.inference_mode():
            lafs, _ = self._detector(int(max_features))(timg)
            desc = self._descriptor(timg, lafs)
        xy = self._kf.get_laf_center(lafs)[0].numpy().astype(np.float64)
        features = Features(to_full_resolution(xy, self.scale), desc[0].numpy().astype(np.float32))
        if mask is None:
            return features
        mask = mask_at(mask, gray.shape)
        col, row = (np.clip(np.round(xy[:, k]), 0, gray.shape[1 - k] - 1).astype(int) for k in (0, 1))
        return features.subset(mask[row, col])
