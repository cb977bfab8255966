"""The scripts' output folders: made at the start, as `mkdir -p` (and as the contactlab program
does), so that a path that cannot be made stops a script before its runs, with one line.

Imported by the scripts beside it (a script's own folder is first on Python's path).
"""
import os
import sys


def make_folder(path, program):
    """Makes the folder `path` and the folders above it that are missing. When it cannot be made
    (a file where a folder should be, no permission): one line on stderr naming it and why, and
    exit status 2 (bad input, as the contactlab program)."""
    try:
        os.makedirs(path or ".", exist_ok=True)
    except OSError as e:
        # The nearest of `path` and the folders above it that exists names what is in the way.
        p = path
        while p and not os.path.lexists(p) and os.path.dirname(p) != p:
            p = os.path.dirname(p)
        if p and os.path.lexists(p) and not os.path.isdir(p):
            why = f"'{p}' is a file, not a folder"
        else:
            why = e.strerror or str(e)
        print(f"{program}: {path}: cannot create the folder: {why}", file=sys.stderr)
        sys.exit(2)


def make_parent_folder(path, program):
    """make_folder for the folder of the file `path` (nothing when it has none)."""
    make_folder(os.path.dirname(path), program)
