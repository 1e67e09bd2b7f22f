"""
Pure-Python core of hand_codesign: tasks, hand model, simulation, objectives, optimizers.

Its rooms (docs/ARCHITECTURE.md): task/ (the schema, reading, checks, genome, Variant), sim/
(hand, worlds, policies, objectives, the PyBullet and MuJoCo engines), search/ (optimizers and
their registry, hierarchy, stages, horizon, resampling, resume), run/ (what the optimizer
node decides), rig/ (hardware in the loop) and experiments/ (the paper's experiments and their
measures); at the root evaluate() and the shared vocabulary (contract, design, rotations,
outcomes).

The names below are loaded on first use (PEP 562), not when the package is imported: the
simulator imports PyBullet, which silences the process's standard streams while it loads, and
the optimizer or an analysis never simulate. ``import hand_codesign.core.task`` loads the task
room alone; ``hand_codesign.core.evaluate`` loads the simulator when it is first touched.
"""

import importlib
import sys
import types

# exported name -> the submodule of core that defines it
_EXPORTS = {
    'decode': 'task.genome', 'genome_spec': 'task.genome', 'GenomeSpec': 'task.genome',
    'objective_names': 'task.genome',
    'evaluate': 'evaluate', 'Evaluation': 'evaluate',
    'Simulator': 'sim.pybullet_sim',
    'load_task': 'task', 'parse_task': 'task', 'Task': 'task', 'TaskError': 'task',
    'grid_world_states': 'sim.worlds', 'world_states': 'sim.worlds', 'WorldState': 'sim.worlds',
}

__all__ = sorted(_EXPORTS, key=str.lower)


def __getattr__(name):
    """Import the submodule that defines an exported name, on first use."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    value = getattr(importlib.import_module(f'{__name__}.{module}'), name)
    globals()[name] = value
    return value


def __dir__():
    """List the exported names beside what is loaded already."""
    return sorted(set(globals()) | set(_EXPORTS))


class _CorePackage(types.ModuleType):
    """
    The package, keeping its exported function ``evaluate`` over the submodule of that name.

    Importing a submodule sets it as an attribute of its package; for ``core.evaluate`` that
    would hide the function ``evaluate`` whenever the submodule was imported first.
    """

    def __setattr__(self, name, value):
        if (isinstance(value, types.ModuleType) and _EXPORTS.get(name) == name
                and value.__name__ == f'{__name__}.{name}'):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _CorePackage
