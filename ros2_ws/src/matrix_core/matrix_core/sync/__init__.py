"""Grouping per-stream messages into synchronised multi-view frames by header stamp."""

from matrix_core.sync.frame_sync import FrameSynchronizer, FrameSyncSettings, SyncedFrame
from matrix_core.sync.stamp_restart import RestartSettings, StampRestart

__all__ = ['FrameSynchronizer', 'FrameSyncSettings', 'RestartSettings', 'StampRestart', 'SyncedFrame']
