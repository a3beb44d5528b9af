"""Output folders named on the command line (``--out``): checked before anything is built.

A path that names a file, or one that lies under a file or where no folder can be made, is
one line naming the option (exit 2), not an ``OSError`` from deep inside a run."""

from __future__ import annotations

import os
from pathlib import Path

from harness.errors import SrrError

__all__ = ["check_out_folder", "file_above", "first_missing", "remove_empty"]


def file_above(path: Path) -> Path | None:
    """The nearest existing folder of ``path``'s when it is in fact a file (no folder can be
    made under it), else None."""
    above = next((p for p in Path(path).parents if p.exists()), None)
    return above if above is not None and not above.is_dir() else None


def first_missing(path: Path) -> Path | None:
    """The outermost folder that making ``path`` would create (``path`` itself when only it
    is missing); None when ``path`` exists. Removing it undoes making ``path``."""
    path = Path(path)
    if path.exists():
        return None
    missing = path
    for parent in path.parents:
        if parent.exists():
            break
        missing = parent
    return missing


def remove_empty(path: Path, made: Path) -> None:
    """Remove ``path`` and its parents up to ``made`` (:func:`first_missing`'s answer before
    ``path`` was made) while they are empty folders: what a command that failed made for a
    folder it then removed."""
    path, made = Path(path), Path(made)
    chain = [path, *path.parents]
    if made not in chain:
        return
    for folder in chain[:chain.index(made) + 1]:
        try:
            folder.rmdir()
        except OSError:  # not empty, or already gone with what was in it
            if folder.exists():
                return


def check_out_folder(path: Path, option: str = "--out") -> None:
    """Refuse ``path`` as an output folder when it is a file, or when it lies under a file or
    a folder where no folder can be made. Nothing is made here: a refused command leaves no
    empty folders behind; the folder is made by whoever writes it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise SrrError(f"{option} {path}: is a file, not a folder")
    above = file_above(path)
    if above is not None:
        raise SrrError(f"{option} {path}: {above} is a file, not a folder")
    missing = first_missing(path)
    if missing is not None and not os.access(missing.parent, os.W_OK | os.X_OK):
        raise SrrError(f"{option} {path}: cannot make the folder {missing}: permission "
                       f"denied in {missing.parent}")
