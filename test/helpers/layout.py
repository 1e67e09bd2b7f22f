"""Where the tests live: test/ mirrors the package, one folder per room, helpers apart."""

import pathlib

TEST = pathlib.Path(__file__).resolve().parents[1]
HELPERS = TEST / 'helpers'
# Every folder that holds tests, the helpers first: a test imports a helper or another room's
# test module (`from test_system import start_run`) by its name, as the session does.
FOLDERS = [HELPERS] + sorted({path.parent for path in TEST.rglob('test_*.py')})
