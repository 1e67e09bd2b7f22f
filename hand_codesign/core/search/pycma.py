"""
pycma, imported without the plotting and statistics packages it loads at import time.

`import cma` also imports matplotlib.pyplot (for cma.plot) and scipy.stats (for a surrogate
model's rank correlation): about 1 s of CPU, most of an optimizer process's start, for
nothing this project calls. While cma is imported, those two packages read as absent (unless
something imported them already), so pycma falls back to its own code paths (it is written
to run without either); they import normally afterwards. CMA-ES itself uses numpy alone, so
its samples and updates do not change.
"""

import sys
import warnings

_SKIPPED = ('matplotlib', 'scipy')


def _import_cma():
    skipped = [name for name in _SKIPPED if name not in sys.modules]
    for name in skipped:
        sys.modules[name] = None  # `import name` raises ImportError
    try:
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')  # "Could not import matplotlib.pyplot ..."
            import cma
    finally:
        for name in skipped:
            if sys.modules.get(name, False) is None:
                del sys.modules[name]
    return cma


cma = _import_cma()
