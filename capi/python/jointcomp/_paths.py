"""Where the distributed jobs write: checked before any work, and names from user data kept inside it.

The same rules as the command-line tool's (cli/output_paths.cpp): an output folder is made if needed and
proved writable before a long run starts, and a name taken from the user's data (a campaign file's name, a
robot's name) becomes one plain file name, so that ``...csv`` or ``../../victim`` cannot lead outside it.
"""

import os
import pathlib
import re
import tempfile

MAX_NAME_LENGTH = 64
_NOT_PLAIN = re.compile(r"[^A-Za-z0-9._-]")


def plain_file_name(text, fallback="robot"):
    """``text`` as one plain file name: letters, digits, '.', '_' and '-' kept, anything else '_', no leading
    dot (so never '.', '..' or a hidden file), at most MAX_NAME_LENGTH characters; ``fallback`` when nothing
    is left."""
    name = _NOT_PLAIN.sub("_", str(text)).lstrip(".")[:MAX_NAME_LENGTH]
    return name or fallback


def prepare_output_folder(folder, error, option="--out"):
    """Makes ``folder`` (and its parents) if needed and proves it writable by creating and removing a file in
    it; raises ``error`` naming ``option``, the path and the reason otherwise. Returns it as a Path."""
    text = os.fspath(folder)
    if not text:
        raise error("%s: the path is empty" % option)
    path = pathlib.Path(text)
    if path.exists() and not path.is_dir():
        raise error("%s: '%s' exists and is not a folder" % (option, text))
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as reason:
        raise error("%s: '%s' cannot be created or written (%s)" % (option, text, reason.strerror or reason)) \
            from None
    return path
