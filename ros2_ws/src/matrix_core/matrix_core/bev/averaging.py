"""Weight averaging over the last epochs of a training run (stochastic weight averaging, Izmailov et al. 2018).

Why: trained on simulated images only, the network's accuracy on real frames swings from epoch to epoch (real
validation MODA 70 -> 92 -> 70 % over three epochs of one seed) while the simulated validation stays flat: which
epoch happens to transfer is luck. The mean of the weights of several epochs sits in a wider, flatter region of
the loss and transfers more evenly. Batch-norm statistics of averaged weights are not the average of the
epochs' statistics, so they are measured again over training samples (:func:`recompute_batch_norm`).
"""

import torch
from torch import nn


def average_state_dicts(state_dicts: list) -> dict:
    """Element-wise mean of floating-point entries of ``state_dicts`` (same keys and shapes); integer entries
    (batch-norm step counters) are taken from the last one."""
    if not state_dicts:
        raise ValueError('no state dicts to average')
    keys = state_dicts[0].keys()
    for sd in state_dicts[1:]:
        if sd.keys() != keys:
            raise ValueError('state dicts to average have different keys (different models?)')
    out = {}
    for k in keys:
        values = [sd[k] for sd in state_dicts]
        if values[0].is_floating_point():
            out[k] = torch.stack([v.float() for v in values]).mean(dim=0).to(values[0].dtype)
        else:
            out[k] = values[-1].clone()
    return out


@torch.no_grad()
def recompute_batch_norm(model: nn.Module, forward_samples) -> int:
    """Reset every batch norm's running mean and variance and measure them again as the plain average over
    the batches that ``forward_samples(model)`` pushes through ``model`` (train mode, no gradients); returns
    the number of batch-norm layers. ``forward_samples`` runs the forward passes (e.g. training steps)."""
    norms = [m for m in model.modules() if isinstance(m, nn.modules.batchnorm._BatchNorm)]
    saved = [m.momentum for m in norms]
    for m in norms:
        m.reset_running_stats()
        m.momentum = None  # cumulative average over all batches seen, not an exponential one
    was_training = model.training
    model.train()
    try:
        forward_samples(model)
    finally:
        for m, momentum in zip(norms, saved):
            m.momentum = momentum
        model.train(was_training)
    return len(norms)
