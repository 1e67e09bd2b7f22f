"""
The task a run actually used: the task file's text plus the run's overrides.

A run records the task file's text as loaded and, apart from it, the values its command line
overrode (seed, budget, world states, physics engine: RunInfo.engine, with the engine's
version in RunInfo.engine_version). A run in several engines (physics.engines) records them
comma-separated in both, in the task's order: 'pybullet,mujoco' and
'pybullet==3.2.7,mujoco==4.0.0'; a run in one engine records it as before. Every process
that needs the run's task (evaluators, replay, analysis, resume) rebuilds it with `run_task`,
so they all agree on it exactly.
"""

import functools

from hand_codesign.core.task import load_task
from hand_codesign.core.task import parse_task
from hand_codesign.core.task.parts import ENGINES

VERSIONED_PACKAGES = ['hand_codesign', 'pybullet', 'cma', 'deap', 'numpy']


def run_task(task_yaml, source, seed, iterations, population, world_states, variant=None,
             engine=''):
    """
    Return the Task of a run from its task text and overrides (0 or None keeps the file's).

    `task_yaml` is the task file's text as the run loaded it (RunInfo.task_yaml), `source` what
    names it in errors (e.g. 'run ID task'); `seed`, `iterations`, `population` and
    `world_states` are the run's overrides (RunInfo's fields); `variant`, a
    core.task.variant.Variant, makes it the version of the run's task a candidate is evaluated
    on (None: the run's task itself); `engine` is the run's physics engine ('pybullet' or
    'mujoco', or several comma-separated: 'pybullet,mujoco'; '': the task file's). Raises
    TaskError (a ValueError) for a text or override the task does not accept, ValueError for
    an unknown engine.
    """
    return with_overrides(parse_task(task_yaml, source=source), seed, iterations, population,
                          world_states, variant, engine)


def load_run_task(path, seed=None, iterations=None, population=None, world_states=None,
                  engine=None, warn_old_names=True):
    """
    Return the Task a run of the task file at path uses (None keeps the file's values).

    warn_old_names: as load_task's (False for a file that records a task).
    """
    task = load_task(path, warn_old_names)
    return with_overrides(task, task.seed if seed is None else seed, iterations, population,
                          world_states, engine=engine)


@functools.lru_cache(maxsize=None)
def engine_version(engine):
    """Return 'name==version' of a physics engine ('pybullet' or 'mujoco') of this process."""
    import importlib.metadata  # see library_versions
    try:
        return f'{engine}=={importlib.metadata.version(engine)}'
    except importlib.metadata.PackageNotFoundError:
        return f'{engine}==unknown'


def engines_text(task):
    """Return RunInfo.engine of a task's run: its engines, comma-separated ('pybullet')."""
    return ','.join(task.physics.engines)


def engines_version(engines):
    """Return RunInfo.engine_version of a run in `engines` (a RunInfo.engine text)."""
    return ','.join(engine_version(engine) for engine in engine_names(engines))


def engine_names(engines):
    """
    Return the engines of a RunInfo.engine text ('pybullet,mujoco') as a tuple, checked.

    Raises ValueError naming an unknown or repeated engine.
    """
    names = tuple(name.strip() for name in str(engines).split(','))
    for name in names:
        if name not in ENGINES:
            raise ValueError(f'physics engine {name!r}: expected one of {", ".join(ENGINES)} '
                             '(several: comma-separated, e.g. pybullet,mujoco)')
    if len(set(names)) != len(names):
        raise ValueError(f'physics engines {engines!r}: each engine once')
    return names


def with_overrides(task, seed, iterations, population, world_states, variant=None, engine=''):
    """
    Return task with a run's overrides applied (0 or None keeps the task's value).

    `variant` (a core.task.variant.Variant: structure, world states, horizon, stage, held-out
    worlds, resampled draw) says which version of the run's task a candidate is evaluated on;
    `engine` the run's physics engine or engines, comma-separated (RunInfo.engine; '' or None:
    the task file's).
    """
    changes = {'seed': int(seed)}
    if engine:
        changes['physics'] = task.physics.with_engines(engine_names(engine))
    if iterations:
        changes['iterations'] = int(iterations)
    if population:
        changes['population'] = int(population)
    if world_states:
        changes['num_world_states'] = int(world_states)
    if variant is not None:
        changes.update(variant.task_changes())
    return task.replace(**changes)


def library_versions():
    """Return 'name==version' of hand_codesign and the libraries results depend on."""
    # imported here: it costs a process about 40 ms, and only the optimizer asks
    import importlib.metadata
    versions = []
    for name in VERSIONED_PACKAGES:
        try:
            versions.append(f'{name}=={importlib.metadata.version(name)}')
        except importlib.metadata.PackageNotFoundError:
            versions.append(f'{name}==unknown')
    return versions
