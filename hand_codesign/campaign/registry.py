"""
The experiments by name: each experiment's module adds itself, as dm_control's domains add tasks.

An experiment's module defines a function that returns its Experiment and decorates it with
`add`; the face of the experiments (hand_codesign.campaign.experiments) imports every module
and orders their experiments. Read them there, not here: here they are only those whose
modules were imported so far.
"""

from typing import Callable, Dict

from hand_codesign.campaign.experiment import Experiment

_ADDED: Dict[str, Experiment] = {}   # by the name of the module that added it


def add(build: Callable[[], Experiment]) -> Callable[[], Experiment]:
    """
    Register the Experiment `build()` returns under its name (a decorator).

    Args:
        build: a function of no arguments that returns one Experiment.

    Returns:
        build itself, so that the module keeps it.

    Raises:
        ValueError: when an experiment of that name is registered already, or the module
            added one before.
    """
    if build.__module__ in _ADDED:
        raise ValueError(f'{build.__module__}: adds a second experiment; one module holds one')
    experiment = build()
    if any(other.name == experiment.name for other in _ADDED.values()):
        raise ValueError(f'{build.__module__}: an experiment named {experiment.name!r} is '
                         'registered already; experiment names are unique')
    _ADDED[build.__module__] = experiment
    return build


def added() -> Dict[str, Experiment]:
    """
    Return the experiments registered so far, by the module that added each.

    Returns:
        a new dict of module name (e.g. 'hand_codesign.campaign.experiments.task1_seeded') to
        Experiment.
    """
    return dict(_ADDED)
