"""Where the distributed jobs write: checked before any work, names from user data kept inside it, and
scratch folders that a killed run does not leave behind for good.

The same rules as the command-line tool's (cli/output_paths.cpp): an output folder is made if needed and
proved writable before a long run starts, and a name taken from the user's data (a campaign file's name, a
robot's name) becomes one plain file name, so that ``...csv`` or ``../../victim`` cannot lead outside it.
"""

import contextlib
import os
import pathlib
import re
import shutil
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


def write_atomically(path, write):
    """Calls ``write(stream)`` to fill a binary stream that becomes ``path`` whole or not at all: an unnamed
    file in its folder (O_TMPFILE), synced, then linked under a temporary name and renamed over ``path``, so
    that a process killed while writing leaves neither half a file nor a temporary (file systems without
    unnamed files get a named temporary, removed on any error)."""
    path = pathlib.Path(path)
    folder = str(path.parent)
    try:
        fd = os.open(folder, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o644)
    except (AttributeError, OSError):
        fd = None
    temporary = path.with_name(".%s.%d.tmp" % (path.name, os.getpid()))
    if fd is None:
        fd = os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY | os.O_CLOEXEC, 0o644)
        named = True
    else:
        named = False
    try:
        with os.fdopen(fd, "wb") as stream:
            write(stream)
            stream.flush()
            os.fsync(stream.fileno())
            os.fchmod(stream.fileno(), 0o644)
            if not named:
                # linkat(AT_SYMLINK_FOLLOW) needs a directory descriptor in Python (else plain link()).
                folder_fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
                try:
                    os.link("/proc/self/fd/%d" % stream.fileno(), temporary.name, src_dir_fd=folder_fd,
                            dst_dir_fd=folder_fd, follow_symlinks=True)
                finally:
                    os.close(folder_fd)
                named = True
        os.replace(temporary, path)
    except BaseException:
        if named:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        raise


# Scratch folders in the temporary root (tempfile.gettempdir()) are named <prefix><pid>-<start>-<random>, the
# pid and start time (/proc's clock ticks since boot) of the process that owns them: a run killed with SIGKILL
# cannot remove its folder (nor Dask's worker space inside it), and the next run removes it once that
# process is gone. The start time tells a reused pid from the owner.
SCRATCH_PREFIXES = ("jointcomp-dask-", "jointcomp-fleet-")


def _start_time(pid):
    """Process ``pid``'s start time as text, "0" when it runs but /proc cannot tell; None when it is gone."""
    try:
        with open("/proc/%d/stat" % pid, "rb") as stream:
            return stream.read().rsplit(b")", 1)[1].split()[19].decode()  # field 22, starttime
    except FileNotFoundError:
        return None
    except (OSError, IndexError):
        pass
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except OSError:  # another user's process: it runs
        pass
    return "0"


def remove_stale_scratch_folders(root=None):
    """Removes this user's scratch folders (SCRATCH_PREFIXES) in ``root`` (the temporary root by default)
    whose owner process is gone; returns their paths. Others, and names of another form, are left alone."""
    root = root or tempfile.gettempdir()
    pattern = re.compile("(?:%s)([0-9]+)-([0-9]+)-" % "|".join(re.escape(p) for p in SCRATCH_PREFIXES))
    removed = []
    try:
        entries = list(os.scandir(root))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.match(entry.name)
        if not match:
            continue
        try:
            if not entry.is_dir(follow_symlinks=False) or entry.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
        except OSError:
            continue
        now = _start_time(int(match.group(1)))
        if now is None or ("0" not in (now, match.group(2)) and now != match.group(2)):
            shutil.rmtree(entry.path, ignore_errors=True)
            removed.append(entry.path)
    return removed


@contextlib.contextmanager
def scratch_folder(prefix):
    """A new scratch folder in the temporary root named for this process (see SCRATCH_PREFIXES), removed on
    leaving; those that killed runs left behind are removed first."""
    if prefix not in SCRATCH_PREFIXES:
        raise ValueError("scratch folder prefix %r is not one of %s" % (prefix, SCRATCH_PREFIXES))
    remove_stale_scratch_folders()
    pid = os.getpid()
    folder = tempfile.mkdtemp(prefix="%s%d-%s-" % (prefix, pid, _start_time(pid) or "0"))
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)
