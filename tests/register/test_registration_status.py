"""The registration status is an enumeration: in the core (``RegistrationStatus``), in the message
(``HomographyStamped`` constants, with the reason beside them) and in the file form (its lower-case name)."""

import numpy as np
import pytest
from matrix_msgs.msg import HomographyStamped

from matrix_core.register.file_frame import registration_from_record, registration_to_record
from matrix_core.register.registration import Registration, RegistrationStatus
from matrix_core.message_fields import registration_from_msg
from matrix_ros.conversions import registration_to_msg


def test_the_message_constants_are_the_core_values():
    for status in RegistrationStatus:
        assert getattr(HomographyStamped, status.name) == status.value


@pytest.mark.parametrize(
    'registration',
    [
        Registration.failed('only 3 inliers (min_inliers 15)', backend='sift'),
        Registration.bad_input('image data too short', backend='sift'),
    ],
)
def test_a_registration_that_is_not_ok_crosses_the_message_with_its_reason(registration):
    msg = registration_to_msg(registration)
    assert msg.status == registration.status and msg.reason == registration.message and not any(msg.h_img_to_ground)
    back = registration_from_msg(msg)
    assert (back.status, back.message, back.ground_H_img) == (registration.status, registration.message, None)


def test_an_ok_registration_keeps_its_note_and_an_unknown_status_is_unusable():
    ground_H_img = np.array([[0.01, 0.0, -5.0], [0.0, 0.01, -3.0], [0.0, 0.0, 1.0]])
    ok = Registration(RegistrationStatus.OK, np.eye(3), ground_H_img, confidence=0.8, message='re-keyed')
    back = registration_from_msg(registration_to_msg(ok))
    assert back.ok and back.message == 're-keyed'
    np.testing.assert_allclose(back.ground_H_img, ground_H_img)
    msg = registration_to_msg(ok)
    msg.status = 7
    unknown = registration_from_msg(msg)
    assert unknown.status == RegistrationStatus.UNUSABLE and '7' in unknown.message


def test_the_file_form_names_the_status():
    record = registration_to_record(Registration.bad_input('corrupt image'))
    assert record['status'] == 'bad_input'
    assert RegistrationStatus.from_name(record['status']) == RegistrationStatus.BAD_INPUT
    assert not registration_from_record(record, 'D1_0000.json').ok
    with pytest.raises(ValueError, match='unknown registration status'):
        RegistrationStatus.from_name('fine')
    assert registration_from_record(record, 'D1_0000.json').status == RegistrationStatus.BAD_INPUT
    assert 'unknown registration status' in registration_from_record({'status': 'fine'}, 'D1_0000.json').message
