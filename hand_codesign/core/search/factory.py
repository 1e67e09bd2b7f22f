"""
The optimizers by name: `make_optimizer(task, dim)` returns the one of `task.algorithm`.

The name-to-class registry sits here, above the classes it names (core.search.optimizers,
core.search.restarts, core.search.quality_diversity), so that none of them needs this module.
"""

from typing import Any, Dict, Optional

from hand_codesign.core.search.optimizers import AskTellOptimizer, CmaEs, MoCmaEs, OptimizerError
from hand_codesign.core.search.quality_diversity import ALGORITHMS as QD_ALGORITHMS
from hand_codesign.core.search.restarts import ALGORITHMS as RESTART_ALGORITHMS
from hand_codesign.core.task.descriptors import DesignDescriptors
from hand_codesign.core.task.genome import seed_genome
from hand_codesign.core.task.parts import ArchiveSpec
from hand_codesign.core.task.spec import Task
from numpy.typing import ArrayLike


def make_optimizer(task: Task, dim: int, first_id: int = 0, seed_x: Optional[ArrayLike] = None,
                   seed: Optional[int] = None) -> AskTellOptimizer:
    """
    Return the optimizer of task.algorithm for a genome of `dim` normalized values.

    Args:
        task: a core.task.Task.
        dim: the genome's size (genome_spec(task).size).
        first_id: the id of its first candidate.
        seed_x: a normalized genome of shape (dim,), values in [0, 1], to start from.
        seed: the optimizer's seed instead of task.seed.

    Returns:
        An ask/tell optimizer (core.search.optimizers.AskTellOptimizer).

    Raises:
        OptimizerError: for an algorithm not in the registry or settings it cannot take.

    cma and mocma are core.search.optimizers'; ipop-cma and bipop-cma (CMA-ES with restarts, which
    also take task.restart_stagnation) are core.search.restarts'; cma-mae and cma-me (quality
    diversity, which also take task.archive and the task's design descriptors)
    core.search.quality_diversity's. It takes population, iteration budget,
    objective weights, initial step size and seed from the task. It starts at `seed_x` if
    given, else at the task's seed design (seeded search, Tasks 1 and 2: the normalized genome
    of `task.seed_design`), else at the centre of the bounds. `seed` replaces task.seed as the
    optimizer's seed (the worlds keep task.seed).
    """
    classes = {'cma': CmaEs, 'mocma': MoCmaEs, **RESTART_ALGORITHMS, **QD_ALGORITHMS}
    if task.algorithm not in classes:
        raise OptimizerError(
            f'task {task.name!r}: algorithm must be one of {sorted(classes)}, got '
            f'{task.algorithm!r}')
    design = task.seed_design
    if seed_x is None and design is not None and design.hand.structure == tuple(task.structure):
        seed_x = seed_genome(task)
    extra: Dict[str, Any] = {}
    if task.algorithm in RESTART_ALGORITHMS:
        extra = {'stagnation': task.restart_stagnation}
    elif task.algorithm in QD_ALGORITHMS:
        extra = _archive_options(task)
    elif task.algorithm == 'cma' and task.worlds.racing is not None:
        extra = {'raced': True}  # core.search.racing
    elif task.algorithm == 'mocma':
        extra = {'front_choice': task.front_choice}
    return classes[task.algorithm](
        dim, task.objective_weights, task.population, task.iterations,
        task.seed if seed is None else seed,
        first_id=first_id, x0=seed_x, sigma0=task.initial_sigma, **extra)


def _archive_options(task):
    """Return the keyword arguments of a quality-diversity optimizer from task.archive."""
    archive = task.archive or ArchiveSpec()
    return {'describe': DesignDescriptors(task, archive.descriptors), 'cells': archive.cells,
            'ranges': archive.ranges, 'emitters': archive.emitters,
            'learning_rate': archive.learning_rate}
