"""Grouping per-stream messages into synchronised multi-view frames by header stamp."""

from matrix_core.sync.frame_sync import FrameSynchronizer, FrameSyncSettings, SyncedFrame

__all__ = ['FrameSynchronizer', 'FrameSyncSettings', 'SyncedFrame']
