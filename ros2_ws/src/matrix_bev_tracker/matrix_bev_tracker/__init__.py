"""Bird's-eye-view multi-view fusion network and tracker: publishes detections and tracks."""

import os

# The fuse process runs the network on ``threads`` torch (OpenMP) threads. OpenMP's default lets idle threads
# spin for a while after each layer; on a machine whose cores the drones share that spinning is pure cost
# (bench_graph.py, threads 2: fuse 0.24 CPU s per simulated frame spinning, 0.20 passive, the same rate). Set
# before torch loads OpenMP, which reads it once; an explicit OMP_WAIT_POLICY in the environment wins.
os.environ.setdefault('OMP_WAIT_POLICY', 'PASSIVE')
