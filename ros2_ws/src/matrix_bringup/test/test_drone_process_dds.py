"""The installed ``drone`` process (matrix_bringup.drone: a drone's register and calib in one process) over DDS.

This test publishes real MATRIX JPEG frames of drone D3 and checks that the one process subscribes them once
(register's subscription; calib subscribes neither the images nor the homography), that calib is guided by
every frame's registration handed over in process, and that what it publishes - ``D3/homography``,
``D3/camera_info``, ``/diagnostics`` from the nodes ``register`` and ``calib`` - is what separate calib and
register nodes compute: the same core on the colour decode of the same JPEG (this process), within the
tolerance of the grey decode, and right against the ground truth; calib runs on a thread of its own, niced
further. Then a corrupt JPEG: both nodes report the bad input and the process keeps running."""

from pathlib import Path

import cv2
import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage
from std_msgs.msg import Header

from matrix_calib.settings import CalibNodeSettings
from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.prior import initial_prior
from matrix_core.calib.scene import config_for_dataset, load_scene
from matrix_core.calib.status import CalibStatus
from matrix_core.datasets import MatrixDataset
from matrix_core.geometry.camera import rotation_angle_deg
from matrix_core.geometry.homography import apply_homography
from matrix_core.register.ground_mask import visible_ground_grid
from matrix_core.register.registrar import Registrar
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import MATRIX_BLOCK
from matrix_register.settings import RegisterNodeSettings
from matrix_core.message_fields import camera_from_camera_info, registration_from_msg, stamp_seconds
from matrix_ros.conversions import image_to_compressed, seconds_to_stamp
from matrix_ros.qos import qos_by_name
from ros_helpers import spin_until, start_node, stop, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEW, FRAMES = 'D3', 5


def _separate_nodes(dataset, config, jpegs):
    """What separate register and calib nodes compute for these JPEGs (the same core, colour decode)."""
    register, _ = settings_for_dataset(RegisterNodeSettings(views=[VIEW]), dataset)
    registrar = Registrar(
        register, dataset.reference_image(VIEW), dataset.reference_camera(VIEW), dataset.area, f'{VIEW}/reference'
    )
    calib = CalibNodeSettings(config=str(config), prior_dataset=str(dataset.root), use_registration=True)
    scene = load_scene(calib.config)
    calibrator = DroneCalibrator(scene, calib, *initial_prior(scene, VIEW, dataset))
    out = []
    for stamp, msg in jpegs:
        image = cv2.imdecode(np.frombuffer(bytes(msg.data), np.uint8), cv2.IMREAD_COLOR)
        registration = registrar.register(image)
        out.append((registration, calibrator.process(image, stamp, registration).camera))
    return out


def _thread_niceness(pid: int) -> dict:
    """thread id -> niceness of every thread of process ``pid`` (/proc/PID/task/TID/stat, field 19)."""
    tasks = Path(f'/proc/{pid}/task')
    return {int(t.name): int((t / 'stat').read_text().rsplit(')', 1)[1].split()[16]) for t in tasks.iterdir()}


def test_drone_process_decodes_once_and_hands_the_registration_to_calib(matrix_sample, node_executable):
    dataset = MatrixDataset(matrix_sample)
    config = config_for_dataset(matrix_sample)
    drone = start_node(
        node_executable('matrix_bringup', 'drone'),
        f'views:=[{VIEW}]',
        'compressed:=true',
        f'reference_dataset:={matrix_sample}',
        f'prior_dataset:={matrix_sample}',
        f'config:={config}',
        'qos:=reliable',
        'use_registration:=true',
        'registration_wait_s:=60.0',
    )
    rclpy.init()
    node = Node('drone_process_test')
    homographies, infos, diags = {}, {}, {}
    images = node.create_publisher(CompressedImage, f'/{VIEW}/image/compressed', qos_by_name('reliable'))
    outputs = [
        node.create_subscription(
            HomographyStamped,
            f'/{VIEW}/homography',
            lambda m: homographies.setdefault(stamp_seconds(m.header.stamp), m),
            10,
        ),
        node.create_subscription(
            CameraInfo, f'/{VIEW}/camera_info', lambda m: infos.setdefault(stamp_seconds(m.header.stamp), m), 10
        ),
        node.create_subscription(
            DiagnosticArray,
            '/diagnostics',
            lambda m: diags.update({(s.name, round(stamp_seconds(m.header.stamp), 3)): s for s in m.status}),
            50,
        ),
    ]
    jpegs = []
    try:
        wait_matched(node, [images, *outputs], [drone], 120)
        # the process's two nodes, under their own names (node names travel after the endpoints: wait)
        named = spin_until(node, lambda: {'calib', 'register'} <= set(node.get_node_names()), [drone], 60)
        readers, homography_readers = images.get_subscription_count(), node.count_subscribers(f'/{VIEW}/homography')
        for k in range(FRAMES):
            stamp = 1.0 + 0.5 * k
            msg = image_to_compressed(
                dataset.load_image(VIEW, dataset.frames[k]),
                Header(stamp=seconds_to_stamp(stamp), frame_id=f'{VIEW}/camera_optical'),
            )
            jpegs.append((stamp, msg))
            images.publish(msg)
            assert spin_until(node, lambda: ('calib/D3', stamp) in diags and stamp in homographies, [drone], 60), stamp
        bad = CompressedImage(header=Header(stamp=seconds_to_stamp(9.0)), format='jpeg', data=b'\xff\xd8' + bytes(50))
        images.publish(bad)
        spin_until(node, lambda: ('calib/D3', 9.0) in diags and ('register/D3', 9.0) in diags, [drone], 60)
        alive, niceness = drone.poll() is None, _thread_niceness(drone.pid)
    finally:
        out = stop(drone)
        node.destroy_node()
        rclpy.shutdown()
    assert named, node.get_node_names()
    assert readers == 1, out  # one image subscription in the process (register's)
    assert homography_readers == 1, out  # this test's: calib takes the registration in process
    assert alive, out
    # calib on a thread of its own (thread_niceness, default 5): niced 5 more than the process's main thread
    assert niceness[drone.pid] + CalibNodeSettings().thread_niceness in niceness.values(), niceness
    for name in ('register/D3', 'calib/D3'):  # a corrupt JPEG: each node says so, the process goes on
        assert diags[(name, 9.0)].level == DiagnosticStatus.ERROR and 'bad_input' in diags[(name, 9.0)].message, out
    separate = _separate_nodes(dataset, config, jpegs)
    for k, ((stamp, _), (registration, camera)) in enumerate(zip(jpegs, separate)):
        truth = dataset.camera(VIEW, dataset.frames[k])
        values = {kv.key: kv.value for kv in diags[('calib/D3', stamp)].values}
        assert CalibStatus.from_name(values['status']) is CalibStatus.OK, (stamp, values, out)
        assert values['guide'] == 'registration', (stamp, values, out)
        live = registration_from_msg(homographies[stamp])
        assert live.ok and registration.ok, (stamp, live.message, registration.message)
        # image -> ground of the same ground points: the drone process against separate nodes and the truth
        world = visible_ground_grid(truth, dataset.area, 1.0, MATRIX_BLOCK)
        pixels = truth.ground_to_img(world)
        ground = apply_homography(live.ground_H_img, pixels)
        assert np.median(np.linalg.norm(ground - apply_homography(registration.ground_H_img, pixels), axis=1)) < 0.05
        assert np.median(np.linalg.norm(ground - world, axis=1)) < 0.1  # metres
        cam = camera_from_camera_info(infos[stamp])
        # grey and colour decodes of one JPEG differ by a grey level here and there: poses by up to ~0.1 deg on
        # D3 (measured), each as close to the truth as the other
        assert rotation_angle_deg(cam.R, camera.R) < 0.15 and np.linalg.norm(cam.center - camera.center) < 0.08
        assert rotation_angle_deg(cam.R, truth.R) < 0.15 and np.linalg.norm(cam.center - truth.center) < 0.08


def test_drone_process_names_a_parameter_neither_node_has(matrix_sample, node_executable):
    """One parameter set for two nodes: each takes the other's names, a name neither has is an error."""
    drone = start_node(
        node_executable('matrix_bringup', 'drone'),
        f'views:=[{VIEW}]',
        f'reference_dataset:={matrix_sample}',
        'registration_wiat_s:=1.0',
    )
    try:
        drone.wait(120)
    finally:
        out = stop(drone)
    assert drone.returncode != 0, out
    assert "register: unknown parameter(s) 'registration_wiat_s' (did you mean 'registration_wait_s'?)" in out, out
