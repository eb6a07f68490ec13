"""Output folders written whole or not at all: staged beside their target, or removed when a command fails.

A refused command must not leave a half-written result (a reader would take
it for a finished one) nor an empty folder it created. ``staged`` writes a
folder's new entries into a temporary folder beside it and moves them in only
when every one was written; ``new_folders`` and ``remove_new`` let a command
that writes in place (the calibration) remove the folders it made when it fails.
"""
from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path


def new_folders(path) -> list:
    """Create ``path`` and its missing parents; return the folders created, outermost first."""
    path = Path(path)
    missing = [p for p in (path, *path.parents) if not p.exists()][::-1]
    path.mkdir(parents=True, exist_ok=True)
    return missing


def remove_new(created) -> None:
    """Remove the folders ``new_folders`` created (the outermost, with whatever was written in it since)."""
    if created:
        shutil.rmtree(created[0], ignore_errors=True)


@contextlib.contextmanager
def staged(out):
    """A temporary folder beside ``out`` whose entries replace ``out``'s of the same name on success.

    Entries (files or folders) written into the yielded folder are moved into
    ``out`` (created if needed) when the block ends without an error, each
    replacing an entry of the same name; on an error the temporary folder is
    removed, with any parent of ``out`` that was created for it, and ``out``
    is left as it was.

    Yields
    ------
    Path
        The temporary folder (``.<name>.<random>`` in ``out``'s parent, so the
        moves are renames on one file system).
    """
    out = Path(out)
    created = new_folders(out.parent)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    except BaseException:
        remove_new(created)
        raise
    try:
        yield tmp
        out.mkdir(exist_ok=True)
        for entry in sorted(tmp.iterdir()):
            target = out / entry.name
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(entry, target)
    except BaseException:
        remove_new(created)
        raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["new_folders", "remove_new", "staged"]
