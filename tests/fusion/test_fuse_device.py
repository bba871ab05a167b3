"""The fuse node's ``device`` parameter is validated at start: a GPU this machine lacks stops the node before it
loads the network or subscribes, naming the device; ``auto`` on a machine without CUDA says in its log that it
chose the CPU."""

import pytest
import torch

from ros_helpers import finish, start_node, stop, wait_for

pytestmark = [pytest.mark.ros, pytest.mark.slow]
MISSING_GPU = f'cuda:{torch.cuda.device_count()}'  # one past the last GPU: cuda:0 on a machine without any


def test_a_missing_gpu_stops_the_fuse_node_at_start(node_executable):
    fuse = start_node(node_executable('matrix_bev_tracker', 'fuse'), f'device:={MISSING_GPU}', 'views:=[D1]')
    log = finish(fuse, 120)
    assert fuse.returncode != 0, log
    assert f"DeviceError: device '{MISSING_GPU}'" in log and 'no CUDA device' in log, log
    assert 'fusing 1 views' not in log  # it never got as far as the network


@pytest.mark.skipif(torch.cuda.is_available(), reason='this machine has a CUDA device: auto chooses it')
def test_auto_says_it_chose_the_cpu(node_executable, tmp_path):
    fuse = start_node(node_executable('matrix_bev_tracker', 'fuse'), 'views:=[D1]', env={'ROS_LOG_DIR': str(tmp_path)})
    try:
        wait_for(
            lambda: 'fusing 1 views' in ''.join(p.read_text() for p in tmp_path.rglob('*.log')), 120, 'fuse to start'
        )
    finally:
        log = stop(fuse)
    assert 'device: auto chose cpu (no CUDA device)' in log, log
