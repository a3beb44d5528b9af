"""Output folders named on the command line (``--out``): checked before anything is built.

A path that names a file, or one that lies under a file or where no folder can be made, is
one line naming the option (exit 2), not an ``OSError`` from deep inside a run."""

from __future__ import annotations

from pathlib import Path

from harness.errors import SrrError

__all__ = ["check_out_folder", "file_above"]


def file_above(path: Path) -> Path | None:
    """The nearest existing folder of ``path``'s when it is in fact a file (no folder can be
    made under it), else None."""
    above = next((p for p in Path(path).parents if p.exists()), None)
    return above if above is not None and not above.is_dir() else None


def check_out_folder(path: Path, option: str = "--out") -> None:
    """Refuse ``path`` as an output folder when it is a file, or when its parent folder does
    not exist and cannot be made (it is made here: an empty folder, nothing that looks like
    output). The folder itself is left to whoever writes it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise SrrError(f"{option} {path}: is a file, not a folder")
    above = file_above(path)
    if above is not None:
        raise SrrError(f"{option} {path}: {above} is a file, not a folder")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise SrrError(f"{option} {path}: cannot make the folder {path.parent}: "
                       f"{err.strerror or err}") from None
