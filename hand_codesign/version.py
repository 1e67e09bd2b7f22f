"""The version of hand_codesign that made a result: the package's, and its source commit."""

import importlib.metadata
import pathlib
import subprocess

# a git checkout holds the package here (`make setup`'s development install); an installed
# copy (colcon, a wheel) has no .git beside it, and then only the package version is known
SOURCE_TREE = pathlib.Path(__file__).resolve().parents[1]


def version_text():
    """Return e.g. '0.1.0 (commit 1e8ff43)', or '0.1.0' outside a git checkout."""
    version = importlib.metadata.version('hand_codesign')
    if not (SOURCE_TREE / '.git').exists():
        return version
    try:
        # --exclude=*: the commit alone, never a tag's name
        commit = subprocess.run(
            ['git', 'describe', '--always', '--dirty', '--abbrev=7', '--exclude=*'],
            cwd=SOURCE_TREE, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return version
    return f'{version} (commit {commit.stdout.strip()})' if commit.returncode == 0 else version
