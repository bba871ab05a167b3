"""``NodeSettings.apply_threads`` bounds every worker pool a node's algorithms use: OpenCV's and numpy's BLAS
(the exact feature matcher's distance matrix is a BLAS product; BLAS threads left at the core count spin on
a loaded machine and cost about twice the CPU time of one)."""

import cv2
from threadpoolctl import threadpool_info, threadpool_limits

from matrix_ros.node_settings import NodeSettings


def test_apply_threads_limits_opencv_and_blas():
    with threadpool_limits(limits=None):  # restores this test process's pools afterwards
        before = cv2.getNumThreads()
        try:
            NodeSettings(threads=1).apply_threads()
            blas = [pool for pool in threadpool_info() if pool['user_api'] == 'blas']
            assert blas, 'numpy should load a BLAS library'
            assert all(pool['num_threads'] == 1 for pool in blas), blas
            assert cv2.getNumThreads() == 1
        finally:
            cv2.setNumThreads(before)
