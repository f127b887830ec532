"""Saving a figure whole or not at all, as the C++ tools write their files (model/io/atomic_file): into a
temporary file in the target's folder, then renamed over the target, so that a run killed while
plotting leaves the old PNG or none, never half of one."""

import os
import tempfile


def save_figure(figure, path, dpi):
    folder = os.path.dirname(os.path.abspath(path))
    handle, temporary = tempfile.mkstemp(prefix=".", suffix=".png.tmp", dir=folder)
    try:
        with os.fdopen(handle, "wb") as stream:
            figure.savefig(stream, dpi=dpi, format="png")
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
