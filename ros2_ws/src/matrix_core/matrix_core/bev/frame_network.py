"""A trained :class:`~matrix_core.bev.model.BevFusionNet` rearranged for inference one frame at a time (live
fusion, offline evaluation): the outputs of ``BevFusionNet.forward`` (to float rounding, tested against it on
real frames) with less work per frame. Profiled on one core (``scripts/profile_fuse.py``), what it saves:

- batch norms folded into the convolutions before them (eval mode: a per-channel affine map);
- only the views present are encoded and warped (forward warps zeros for the missing ones), and a view's
  sampling taps are computed once per distinct ``feat_H_grid`` (a static camera: once);
- the warp gathers each bilinear tap's channels as one row of channels-last features (``lifting_taps``,
  ``F.embedding_bag``) instead of ``F.grid_sample`` on NCHW maps, straight into the aggregation's
  channels-last input;
- pooling: the lifted features are >= 0 (the encoder ends in a ReLU, bilinear sampling keeps the sign) and 0
  where a view does not see the cell, so the masked mean's sum is the plain sum and the masked max the plain
  max (``aggregation.masked_view_pool`` builds masked copies of the (V, C, R, Q) features);
- the temporal block's two passes (with the previous features, for the heads; without, the features handed
  to the next frame) share the convolution of the current features: its first convolution is linear in its
  input (current, previous, flag) and is split by input channels;
- the tracking and offset heads are evaluated only at the heatmap's peaks, the only cells decoding reads.

The weights are a snapshot taken at construction (a model trained further needs a new instance).
"""

import copy

import torch
import torch.nn.functional as F
from torch import nn
from torch.nn.utils.fusion import fuse_conv_bn_eval

from matrix_core.bev.lifting import lifting_taps
from matrix_core.device import model_device

CL = torch.channels_last


def fold_batch_norms(module: nn.Module) -> nn.Module:
    """A copy of ``module`` (eval mode) in which every BatchNorm2d that directly follows a Conv2d inside an
    ``nn.Sequential`` is folded into that convolution (the batch norm becomes an identity)."""
    module = copy.deepcopy(module).eval()
    for seq in [m for m in module.modules() if isinstance(m, nn.Sequential)]:
        for i in range(len(seq) - 1):
            if isinstance(seq[i], nn.Conv2d) and isinstance(seq[i + 1], nn.BatchNorm2d):
                seq[i], seq[i + 1] = fuse_conv_bn_eval(seq[i], seq[i + 1]), nn.Identity()
    return module


class FrameResult:
    """One frame: ``heatmap`` (1, R, Q) logits; ``fused`` (1, C, R, Q) the features the heads read (for
    :meth:`FrameNetwork.heads_at`); ``carry`` (1, C, R, Q) the features to pass as ``previous`` next frame
    (``BevFusionNet.forward``'s ``bev``). Only the next frame needs the carry: it is computed when first read
    (or by :meth:`FrameNetwork.prepare_next`), so that this frame's detections need not wait for it.

    Args: ``carry`` the tensor or a function of no argument that computes it.
    """

    def __init__(self, heatmap: torch.Tensor, fused: torch.Tensor, carry):
        self.heatmap, self.fused, self._carry = heatmap, fused, carry
        self.previous_term = None  # the carry's term in the next frame's temporal convolution, once computed

    @property
    def carry(self) -> torch.Tensor:
        if callable(self._carry):
            with torch.no_grad():
                self._carry = self._carry()
        return self._carry


class FrameNetwork:
    """Args: ``model`` a BevFusionNet (its weights are copied), ``grid_shape`` (rows, cols) of the BEV grid.

    Call with one frame: ``images`` (V, 3, h, w), ``feat_H_grid`` (V, 3, 3), ``view_mask`` (V,) bool and
    ``previous``, the last frame's :class:`FrameResult` or its carry (1, C, R, Q), or None -> :class:`FrameResult`.
    No gradients.

    It runs on the model's device (:attr:`device`): the images of the views present are copied there once per
    frame (no copy on the CPU), the sampling taps are computed there, and every output stays there.
    ``feat_H_grid`` and ``view_mask`` may stay on the CPU (3x3 numbers a view: the keys of the taps' cache).
    """

    def __init__(self, model, grid_shape: tuple):
        fuse = getattr(model.encoder, 'fuse', None)
        if not (isinstance(fuse, nn.Sequential) and isinstance(fuse[-1], nn.ReLU)):
            raise ValueError(
                'FrameNetwork needs non-negative encoder features (an encoder ending in a ReLU): '
                'its pooling relies on them'
            )
        self.grid_shape, self.stride = tuple(grid_shape), model.stride
        self.device = model_device(model)
        # channels_last: on one core the encoder measured 1.15x and the aggregation up to 1.8x faster than on
        # NCHW tensors; elsewhere no clear difference on this shared machine (scripts/bench_routes.py)
        self.encoder = fold_batch_norms(model.encoder).to(memory_format=CL)
        self.aggregate = fold_batch_norms(model.aggregate.convs).to(memory_format=CL)
        self.heads = copy.deepcopy(model.heads).eval().to(memory_format=CL)
        self._taps = {}  # view index -> (feat_H_grid bytes, lifting_taps: (R*Q, 4) index, (R*Q, 4) weight, (R*Q,) seen)
        self.temporal = None
        if model.temporal is not None:
            convs = fold_batch_norms(model.temporal.convs).to(memory_format=CL)
            first, c = convs[0], model.heads.heatmap[0].in_channels
            w = first.weight.detach()
            self.temporal = {
                'current': w[:, :c].contiguous(memory_format=CL),
                'previous': w[:, c : 2 * c].contiguous(memory_format=CL),
                'bias': first.bias.detach(),
                # the flag channel (1 with a previous frame) through the zero-padded convolution: fixed per grid
                'flag': F.conv2d(
                    torch.ones(1, 1, *self.grid_shape, device=w.device), w[:, 2 * c :], padding=first.padding
                ).contiguous(memory_format=CL),
                'rest': convs[1:],
            }

    @torch.no_grad()
    def __call__(self, images, feat_H_grid, view_mask, previous=None) -> FrameResult:
        views = torch.nonzero(view_mask.bool()).flatten().tolist()
        n_views = len(view_mask)
        rows, cols = self.grid_shape
        if views:
            present = images if len(views) == n_views else images[views]  # no copy when every view is there
            feats = self.encoder(present.to(self.device).contiguous(memory_format=CL))
            pooled = self._lift_and_pool(feats, self._taps_of(views, feat_H_grid, feats.shape[-2:]), n_views)
        else:
            pooled = torch.zeros(
                1, 2 * self.encoder.out_channels + 1, rows, cols, dtype=images.dtype, device=self.device
            )
            pooled = pooled.contiguous(memory_format=CL)
        aggregated = self.aggregate(pooled)
        if self.temporal is None:
            return FrameResult(self._heatmap(aggregated), aggregated, aggregated)
        t = self.temporal
        current = F.conv2d(aggregated, t['current'], t['bias'], padding=1)

        def carry():  # the pass without the previous features: what the next frame gets
            return aggregated + t['rest'](torch.relu(current))

        if previous is None:
            fused = carry = carry()  # the heads read it now
        else:
            with_previous = current + self._previous_term(previous) + t['flag']
            fused = aggregated + t['rest'](torch.relu(with_previous))
        return FrameResult(self._heatmap(fused), fused, carry)

    @torch.no_grad()
    def prepare_next(self, result: FrameResult) -> None:
        """Compute now what the next frame needs of ``result``: its carry and the carry's convolution in the next
        frame's temporal block (otherwise computed by the next call; a live node calls this after publishing the
        frame, so that neither the frame's results nor the next frame wait for them: ~0.03 s on one core)."""
        if self.temporal is not None:
            self._previous_term(result)

    def _previous_term(self, previous):
        """conv(previous carry) with the temporal block's weights of the previous features (kept on a
        :class:`FrameResult`)."""
        if isinstance(previous, FrameResult):
            if previous.previous_term is None:
                previous.previous_term = self._previous_term(previous.carry)
            return previous.previous_term
        return F.conv2d(previous, self.temporal['previous'], padding=1)

    def warm_up(self, n_views: int, image_size: tuple) -> None:
        """One frame of ``n_views`` zero images of (w, h) ``image_size``, without and with previous features: the
        first calls of each convolution build its kernels (measured ~0.1 s more on one core over the first two
        frames), which a live graph's first frames should not pay. Nothing is kept (outputs, sampling taps)."""
        w, h = image_size
        images, mask = torch.zeros(n_views, 3, h, w, device=self.device), torch.ones(n_views, dtype=torch.bool)
        identity = torch.eye(3).repeat(n_views, 1, 1)  # any finite warp: the grid's cells see the image's
        first = self(images, identity, mask)
        cell = torch.zeros(1, dtype=torch.long, device=self.device)
        self.heads_at(self(images, identity, mask, first.carry).fused, cell, cell, True)
        self._taps.clear()

    def _taps_of(self, views: list, feat_H_grid, feat_size) -> list:
        """Each view's (index, weight, seen) of :func:`lifting_taps`, kept while its feat_H_grid stays the same (a
        static camera: computed once; the changed ones in one call)."""
        keys = {v: feat_H_grid[v].cpu().numpy().tobytes() for v in views}
        changed = [v for v in views if self._taps.get(v, (None,))[0] != keys[v]]
        if changed:
            fh = feat_H_grid[changed].to(self.device)
            for v, *taps in zip(changed, *lifting_taps(fh, feat_size, self.grid_shape)):
                self._taps[v] = (keys[v], *taps)
        return [self._taps[v][1:] for v in views]

    def _lift_and_pool(self, feats, taps: list, n_views: int):
        """(1, 2C + 1, R, Q) channels-last: per cell the mean and the max over views of the features lifted to it
        and the share of the ``n_views`` that see it. ``feats`` (K, C, h, w) of the views present, ``taps`` theirs.

        The lifting samples as ``F.grid_sample`` on :func:`sampling_grid` does, but gathers each tap's C channels as
        one row of the channels-last features (:func:`lifting_taps`, ``F.embedding_bag``), and the pooled maps are
        written into one channels-last buffer, the aggregation's input: no concatenation and no layout copies.
        On one core, 8 views: taps 5 + lifting and pooling 3 ms against 5 + 13.6 + 7 (sampling grids, grid_sample,
        concatenation and copies) before."""
        k, c, h, w = feats.shape
        index = torch.cat([t[0] + i * h * w for i, t in enumerate(taps)])
        weight = torch.cat([t[1] for t in taps])
        table = feats.permute(0, 2, 3, 1).reshape(k * h * w, c)  # a view of channels-last features
        lifted = F.embedding_bag(index, table, per_sample_weights=weight, mode='sum').reshape(k, -1, c)
        count = torch.stack([t[2] for t in taps]).sum(dim=0)[:, None]
        rows, cols = self.grid_shape
        pooled = lifted.new_empty(rows * cols, 2 * c + 1)
        torch.div(lifted.sum(dim=0), count.clamp(min=1.0), out=pooled[:, :c])
        torch.amax(lifted, dim=0, out=pooled[:, c : 2 * c])
        torch.div(count, n_views, out=pooled[:, 2 * c :])
        return pooled.reshape(1, rows, cols, 2 * c + 1).permute(0, 3, 1, 2)

    def _heatmap(self, fused):
        return self.heads.heatmap(fused)[0]

    @torch.no_grad()
    def heads_at(self, fused, rows, cols, offset: bool = False) -> tuple:
        """(tracking (N, 2), offset (N, 2) or None) of the heads at the (N,) cells ``rows``, ``cols`` of
        ``fused`` (1, C, R, Q): each head's 3x3 convolution on the cell's zero-padded 3x3 neighbourhood."""
        padded = F.pad(fused[0], (1, 1, 1, 1))
        d = torch.arange(3, device=fused.device)
        patches = padded[:, rows[:, None, None] + d[None, :, None], cols[:, None, None] + d[None, None, :]]
        patches = patches.permute(1, 0, 2, 3).reshape(len(rows), padded.shape[0] * 9)  # (N, C*3*3) as the weight

        def at(head):
            conv, last = head[0], head[2]
            hidden = torch.relu(patches @ conv.weight.reshape(conv.out_channels, -1).T + conv.bias)
            return hidden @ last.weight.reshape(last.out_channels, -1).T + last.bias

        return at(self.heads.tracking), at(self.heads.offset) if offset else None
