"""The ``threads`` setting: one name, one meaning, in every process that takes it (the nodes' wiring,
``matrix_ros.node_settings``, and the fusion's, ``matrix_core.fusion.settings``)."""

from dataclasses import dataclass, field

from matrix_core.settings import Settings


@dataclass
class ThreadSettings(Settings):
    threads: int = field(
        default=1,
        metadata={
            'help': "worker threads of each CPU library pool of this process (OpenCV's, numpy's BLAS, torch's where "
            'the network runs; 1: one core; idle pool threads of many processes on few cores cost CPU)'
        },
    )

    def check(self) -> None:
        if self.threads < 1:
            raise ValueError(f'threads must be >= 1, got {self.threads}')
