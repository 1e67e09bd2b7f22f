"""
Outputs of a verb appear whole or not at all.

A verb writes each output file or folder under a hidden temporary name beside it and moves it
into place once it is complete, so a verb that fails (a bad bag, Ctrl-C, a full disk, a
missing library) leaves nothing that a retry refuses ("already exists") or that a reader takes
for a result. A process killed outright may leave a hidden `.NAME-partial-PID` behind; it
blocks nothing.
"""

import contextlib
import os
import pathlib
import shutil

from hand_codesign.errors import UserError


@contextlib.contextmanager
def staged(path):
    """
    Yield a temporary path beside `path`; once the block ends normally, move it to `path`.

    The block creates the temporary path as a file or a folder. A folder that exists already
    receives the staged files one by one (each replaced whole, others left as they are);
    anything else is renamed into place. If the block raises, the temporary path is removed.
    """
    path = pathlib.Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UserError(f'{path}: cannot create its folder: {error}') from None
    temporary = path.with_name(f'.{path.stem}-partial-{os.getpid()}{path.suffix}')
    remove(temporary)
    try:
        yield temporary
        move_into_place(temporary, path)
    finally:
        remove(temporary)


def move_into_place(temporary, path):
    """Rename temporary to path; a folder onto an existing folder moves entry by entry."""
    if temporary.is_dir() and path.is_dir():
        for entry in temporary.iterdir():
            move_into_place(entry, path / entry.name)
        temporary.rmdir()
    else:
        os.replace(temporary, path)


def remove(path):
    """Remove a file or a folder tree if it exists."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
