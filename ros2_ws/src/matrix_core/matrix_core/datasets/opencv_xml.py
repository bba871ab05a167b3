"""Reading and writing OpenCV FileStorage XML calibration files."""

from pathlib import Path

import cv2
import numpy as np

from matrix_core.datasets.types import DatasetError
from matrix_core.output_paths import atomic_path


def read_matrices(path: Path, names, optional=()) -> dict:
    """Read the named matrices from an OpenCV FileStorage file (ASCII or base64 binary data).

    Nodes holding plain text numbers (Wildtrack's ``<rvec>1 2 3</rvec>``) are read as float vectors.
    ``optional`` nodes are read when present and left out of the result when absent.
    Raises :class:`DatasetError` naming the file and node on any problem.
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f'calibration file not found: {path}')
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as exc:  # truncated or malformed XML: OpenCV's parser raises in the constructor
        why = str(exc.__cause__ or exc).strip().split('error: ')[-1]  # cv2.error wrapped in a SystemError
        raise DatasetError(f'cannot parse calibration file {path}: {why}') from None
    try:
        if not fs.isOpened():
            raise DatasetError(f'cannot parse calibration file: {path}')
        out = {}
        for name in list(names) + list(optional):
            node = fs.getNode(name)
            if node.empty():
                if name in optional:
                    continue
                raise DatasetError(f'{path}: missing node <{name}>')
            if node.isSeq():
                mat = np.array([node.at(i).real() for i in range(node.size())])
            elif node.isString():
                try:
                    mat = np.array([float(v) for v in node.string().split()])
                except ValueError as exc:
                    raise DatasetError(f'{path}: node <{name}> is not numeric') from exc
            else:
                mat = node.mat()
            if mat is None or not np.all(np.isfinite(mat)):
                raise DatasetError(f'{path}: node <{name}> is empty or not finite')
            out[name] = np.asarray(mat, dtype=np.float64)
        return out
    finally:
        fs.release()


def write_matrices(path: Path, matrices: dict) -> None:
    """Write named float64 matrices to an OpenCV FileStorage XML file (creating parent folders)."""
    with atomic_path(path) as tmp:  # a reader never finds half a calibration file
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        try:
            for name, mat in matrices.items():
                fs.write(name, np.asarray(mat, dtype=np.float64))
        finally:
            fs.release()
