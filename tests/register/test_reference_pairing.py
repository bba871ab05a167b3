"""The register node's reference pairing, stamp by stamp (pure: no ROS)."""

from matrix_core.register.reference_pairing import FAIL, HOLD, REFERENCE, REGISTER, ReferencePairing

S = 1_000_000_000


def kinds(steps):
    return [(s.kind, s.stamp_ns) for s in steps]


def test_image_then_its_camera_info_makes_the_reference_and_releases_the_held():
    p = ReferencePairing(max_pending=5)
    assert kinds(p.image(1 * S, 'a')) == [(HOLD, S)]
    assert kinds(p.image(2 * S, 'b')) == [(HOLD, 2 * S)]
    assert p.camera_info(3 * S, 'info3') == []  # no image of that stamp yet
    ref = p.camera_info(2 * S, 'info2')
    assert kinds(ref) == [(REFERENCE, 2 * S)] and ref[0].image == 'b' and ref[0].camera_info == 'info2'
    after = p.started_with(2 * S)
    assert kinds(after) == [(FAIL, S)] and 'before the reference' in after[0].reason
    assert kinds(p.image(4 * S, 'c')) == [(REGISTER, 4 * S)]
    assert p.camera_info(5 * S, 'late') == [] and p.camera_infos == {}


def test_camera_info_first_and_newer_held_images_are_registered_in_order():
    p = ReferencePairing()
    p.camera_info(1 * S, 'info1')
    p.image(3 * S, 'c')
    p.image(2 * S, 'b')
    ref = p.image(1 * S, 'a')
    assert kinds(ref) == [(REFERENCE, S)] and not p.started
    assert kinds(p.started_with(S)) == [(REGISTER, 2 * S), (REGISTER, 3 * S)]


def test_too_many_waiting_images_fail_the_oldest_and_an_unconfirmed_reference_changes_nothing():
    p = ReferencePairing(max_pending=2)
    p.image(1 * S, 'a')
    p.image(2 * S, 'b')
    steps = p.image(3 * S, 'c')
    assert kinds(steps) == [(HOLD, 3 * S), (FAIL, S)] and '1.000000000' in steps[1].reason
    ref = p.camera_info(2 * S, 'bad info')
    assert kinds(ref) == [(REFERENCE, 2 * S)]
    # the node could not make it the reference (bad CameraInfo): it does not confirm; nothing started
    assert not p.started and kinds(p.image(4 * S, 'd')) == [(HOLD, 4 * S)]


def test_camera_infos_kept_are_bounded():
    p = ReferencePairing(max_camera_infos=3)
    for k in range(5):
        p.camera_info(k * S, k)
    assert sorted(p.camera_infos) == [2 * S, 3 * S, 4 * S]
