"""The annotated public faces pass the type checker (mypy, pinned; its settings in setup.cfg)."""

import pathlib

from mypy import api

ROOT = pathlib.Path(__file__).resolve().parents[2]
# The modules whose public faces carry type hints; a module joins when its faces are annotated.
# mypy checks the annotated functions of these and reads what they import for its types only.
TYPED_MODULES = [
    'hand_codesign/core/evaluate.py',
    'hand_codesign/core/task/reader.py',
    'hand_codesign/core/search/search.py',
    'hand_codesign/core/search/factory.py',
    'hand_codesign/bag/reader.py',
    'hand_codesign/bag/writer.py',
    'hand_codesign/campaign/registry.py',
]


def test_the_annotated_modules_type_check():
    # in this process (mypy's API), its cache in build/: a first run takes about 20 s of CPU
    # (numpy's stubs and the modules imported), a later one about 2 s
    stdout, stderr, status = api.run([
        '--config-file', str(ROOT / 'setup.cfg'),
        '--cache-dir', str(ROOT / 'build' / 'mypy_cache'),
        *(str(ROOT / module) for module in TYPED_MODULES)])
    assert status == 0, f'mypy found type errors:\n{stdout}{stderr}'
