"""Where a command may write, and how: never into one of its inputs, never over an earlier output unless
asked, and never a file that looks complete before it is.

:func:`check_output` is called by every writing command before any work; :func:`atomic_write_text` and
:func:`atomic_path` write a file under a temporary name in the same folder and move it into place when it
is complete (``os.replace``: a reader sees the old file or the whole new one, never half of one);
:func:`atomic_folder` does the same for a folder written in several steps (a bag).
"""

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


class OutputError(ValueError):
    """An output path that would overwrite an input or an earlier output."""


def _resolved(path) -> Path:
    return Path(os.path.abspath(os.path.realpath(os.fspath(path))))


def _overlaps(out: Path, source: Path) -> str:
    """How ``out`` overlaps ``source`` ('' when it does not), both resolved."""
    if out == source:
        return 'is'
    if source.is_relative_to(out):
        return 'contains'
    if out.is_relative_to(source):
        return 'lies inside'
    return ''


def check_output(out, inputs=(), overwrite: bool = False, flag: str = '--out') -> Path:
    """``out`` as a Path once it is safe to write: :class:`OutputError` naming the input when ``out`` is,
    contains or lies inside one of ``inputs`` (files or folders; None entries ignored; symlinks followed, so
    a link to the input is the input), and when ``out`` exists and is not empty unless ``overwrite``.

    Args:
        out: the output file or folder.
        inputs: the command's input paths.
        overwrite: accept an existing non-empty ``out`` (the command's ``--overwrite``).
        flag: the option that named ``out``, for the message.
    """
    out = Path(out)
    target = _resolved(out)
    for source in inputs:
        if source is None or source == '':
            continue
        how = _overlaps(target, _resolved(source))
        if how:
            raise OutputError(f'{flag} {out} {how} the input {source}: refusing to write into an input')
    if out.is_file() or out.is_symlink():
        if not out.is_file() or out.stat().st_size:
            if not overwrite:
                raise OutputError(f'{flag} {out} exists; --overwrite replaces it')
    elif out.is_dir() and any(out.iterdir()) and not overwrite:
        raise OutputError(f'{flag} {out} exists and is not empty; --overwrite writes into it')
    return out


def add_overwrite_argument(parser) -> None:
    """The ``--overwrite`` flag of a writing command (read back as ``args.overwrite``)."""
    parser.add_argument(
        '--overwrite', action='store_true', help='write into an existing non-empty output (default: refuse)'
    )


def _temporary_name(path: Path) -> Path:
    """A fresh name beside ``path`` that keeps its suffix (writers such as cv2.imwrite choose the format by it)
    and starts with a dot, so that no reader globbing ``*.json`` or ``0000.*`` takes it for a result."""
    fd, name = tempfile.mkstemp(prefix=f'.{path.stem}.', suffix=f'.partial{path.suffix}', dir=path.parent)
    os.close(fd)
    return Path(name)


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path`` for a writer that takes a file name (cv2, matplotlib,
    FileStorage); on leaving without an exception it replaces ``path``, else it is removed.
    The parent folder is created."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary_name(path)
    try:
        yield tmp
        if not tmp.is_file() or tmp.stat().st_size == 0:
            raise OSError(f'nothing was written to {path}')
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file (see :func:`atomic_path`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary_name(path)
    try:
        tmp.write_bytes(data)  # no fsync: this guards against an interrupted process, not a power cut
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def atomic_write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through a temporary file (see :func:`atomic_path`)."""
    return atomic_write_bytes(path, text.encode('utf-8'))


@contextmanager
def atomic_folder(path):
    """Yield a temporary folder beside ``path`` (which must not exist) to fill; on leaving without an
    exception it is renamed to ``path``, else it is deleted with everything in it."""
    path = Path(path)
    if path.exists():
        raise OutputError(f'{path} exists')
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f'.{path.name}.', suffix='.partial', dir=path.parent))
    work = tmp / path.name  # writers that create their own folder (rosbag2) get one that does not exist yet
    try:
        yield work
        os.rename(work, path)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
