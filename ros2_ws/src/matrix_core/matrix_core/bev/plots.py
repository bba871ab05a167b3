"""PNG pictures of BEV results: heatmap with ground truth and detections, trajectories (GT vs predicted)."""

from pathlib import Path

import numpy as np
from matrix_core.output_paths import atomic_path


def _plt():
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    return plt


def save_heatmap_png(path, heatmap: np.ndarray, grid, gt_xy: np.ndarray, det_xy: np.ndarray, title: str = '') -> Path:
    """Heatmap (R, Q) in [0, 1] over the grid in world metres, ground truth (green circles) and
    detections (red crosses)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 6), dpi=110)
    ax.imshow(
        heatmap, origin='lower', extent=(grid.x_min, grid.x_max, grid.y_min, grid.y_max), cmap='magma', vmin=0, vmax=1
    )
    if len(gt_xy):
        ax.scatter(gt_xy[:, 0], gt_xy[:, 1], s=40, facecolors='none', edgecolors='lime', label='ground truth')
    if len(det_xy):
        ax.scatter(det_xy[:, 0], det_xy[:, 1], s=25, marker='x', c='red', label='detections')
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    ax.set_title(title)
    ax.legend(loc='upper right', fontsize=7)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, bbox_inches='tight')
    plt.close(fig)
    return path


def save_trajectories_png(path, gt, tracks, grid, title: str = '') -> Path:
    """Ground-truth trajectories (thin grey) and predicted tracks (one colour per id), world metres."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.5), dpi=110, sharex=True, sharey=True)
    cmap = plt.get_cmap('tab20')
    for ax, pts, name in ((axes[0], gt, 'ground truth'), (axes[1], tracks, 'predicted tracks')):
        for k, i in enumerate(np.unique(pts.ids) if len(pts) else []):
            sel = pts.ids == i
            order = np.argsort(pts.frames[sel])
            xy = pts.xy[sel][order]
            ax.plot(xy[:, 0], xy[:, 1], '-', lw=1.2, color=cmap(k % 20))
            ax.plot(xy[-1:, 0], xy[-1:, 1], 'o', ms=3, color=cmap(k % 20))
        ax.set_title(f'{name} ({len(np.unique(pts.ids)) if len(pts) else 0} ids)')
        ax.set_xlim(grid.x_min, grid.x_max)
        ax.set_ylim(grid.y_min, grid.y_max)
        ax.set_aspect('equal')
        ax.set_xlabel('x (m)')
    axes[0].set_ylabel('y (m)')
    fig.suptitle(title)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, bbox_inches='tight')
    plt.close(fig)
    return path
