"""Decoding an encoded image (JPEG, PNG) only when it is whole: the one check every image reader makes.

libjpeg decodes a JPEG cut short without an error: it warns "Premature end of JPEG file" on stderr and
fills the missing rows with grey, so ``cv2.imdecode`` returns an image that looks valid. A decoder's
result is therefore not proof of a good image; the file's own end markers are: a JPEG's last scan
(``FF DA``) must be followed by its end-of-image marker (``FF D9``; entropy-coded data never holds that pair,
so it cannot appear before the cut), a PNG must hold its ``IEND`` chunk.
"""

import cv2
import numpy as np

JPEG_START, JPEG_SCAN, JPEG_END = b'\xff\xd8', b'\xff\xda', b'\xff\xd9'
PNG_SIGNATURE, PNG_END = b'\x89PNG\r\n\x1a\n', b'IEND'


class CorruptImage(ValueError):
    """Encoded image data that is empty, cut short or cannot be decoded."""


def as_bytes(data) -> bytes:
    """bytes, bytearray, memoryview, array.array, list or a numpy uint8 array -> bytes."""
    if isinstance(data, bytes):
        return data
    if isinstance(data, np.ndarray):
        return data.astype(np.uint8, copy=False).tobytes()
    return bytes(data)


def check_complete(data) -> None:
    """:class:`CorruptImage` with the reason when a JPEG or PNG ``data`` is empty or cut short (other formats
    are left to the decoder)."""
    data = as_bytes(data)
    if not data:
        raise CorruptImage('empty image data (0 bytes)')
    if data.startswith(JPEG_START):
        scan, end = data.rfind(JPEG_SCAN), data.rfind(JPEG_END)
        if scan < 0:
            raise CorruptImage(f'JPEG without image data (no start-of-scan marker, {len(data)} bytes)')
        if end < scan:
            raise CorruptImage(f'truncated JPEG: no end-of-image marker after its last scan ({len(data)} bytes)')
    elif data.startswith(PNG_SIGNATURE) and data.rfind(PNG_END) < 0:
        raise CorruptImage(f'truncated PNG: no IEND chunk ({len(data)} bytes)')


def decode_image(data, flags: int = cv2.IMREAD_COLOR) -> np.ndarray:
    """Whole encoded image ``data`` -> the array ``cv2.imdecode`` makes with ``flags`` ((H, W, 3) BGR uint8 by
    default); :class:`CorruptImage` when it is cut short or the decoder refuses it."""
    check_complete(data)
    buf = np.frombuffer(as_bytes(data), np.uint8)
    image = cv2.imdecode(buf, flags)
    if image is None:
        raise CorruptImage(f'cannot decode image data ({len(buf)} bytes)')
    return image
