"""
A finished run's design measured on worlds it never trained on, as a campaign caches it.

The run's final design (analysis.records.final_design) and, for a hierarchy, each structure's
best, measured by core.experiments.measures on the budget's unseen worlds of the run's seed;
the per-world measures kept as JSON values (floats exact), so that tables and bands are
recomputed from them without simulating again.
"""

import ast

from hand_codesign.analysis import records
from hand_codesign.campaign.experiment import pinned_dir
from hand_codesign.core.experiments.measures import measure_worlds
from hand_codesign.core.experiments.measures import summarize
from hand_codesign.core.experiments.measures import unseen_world_states
from hand_codesign.core.experiments.measures import with_pose_error
from hand_codesign.core.experiments.measures import WorldMeasures
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant
import numpy as np


def structure_bests(bags):
    """Return {structure: (fitness, candidate id, bag)} of the best OK evaluation per structure."""
    bests = {}
    for bag in bags:
        record = records.open_run(bag, warn=False)
        candidates = record.candidates
        if not len(candidates):
            continue
        structure_of = {}
        for index, candidate_id in enumerate(np.asarray(candidates['candidate_id']).tolist()):
            structure_of.setdefault(int(candidate_id), tuple(
                int(joints) for joints in np.ravel(candidates['structure'][index])))
        rows = records.evaluation_rows(record)
        for index in np.flatnonzero(rows.ok):
            candidate_id = int(rows.candidate_id[index])
            structure = structure_of.get(candidate_id)
            fitness = float(rows.fitness[index])
            if structure is not None and (structure not in bests
                                          or fitness < bests[structure][0]):
                bests[structure] = (fitness, candidate_id, bag)
    return bests


def world_measures_dict(measures):
    """Return WorldMeasures as JSON values (floats exact)."""
    return {'errors': {kind: values.tolist() for kind, values in measures.errors.items()},
            'initial_errors': {kind: values.tolist()
                               for kind, values in measures.initial_errors.items()},
            'collisions': measures.collisions.tolist(),
            'limit_contacts': measures.limit_contacts.tolist(),
            'limit_reached': measures.limit_reached.tolist()}


def world_measures_of(values):
    """Return the WorldMeasures of world_measures_dict()'s output."""
    return WorldMeasures(
        with_pose_error({kind: np.asarray(errors, dtype=float)
                         for kind, errors in values['errors'].items()}),
        with_pose_error({kind: np.asarray(errors, dtype=float)
                         for kind, errors in values['initial_errors'].items()}),
        np.asarray(values['collisions'], dtype=bool),
        np.asarray(values['limit_contacts'], dtype=bool),
        np.asarray(values['limit_reached'], dtype=bool))


def result_design(result, preset, engine):
    """
    Return (task, normalized genome) of a run's committed result record, without its bag.

    result: the parsed `result-RUN.json` of a campaign (its 'design' maps gene names to
    values, as a dict or its repr; 'seed' and 'structure' are the run's); preset: the pinned
    preset's file name in config/reproduce/ the run used; engine: 'pybullet' or 'mujoco'.
    """
    design = result['design']
    if isinstance(design, str):  # written as the dict's repr
        design = ast.literal_eval(design)
    task = run_task((pinned_dir() / preset).read_text(), f'config/reproduce/{preset}',
                    int(result['seed']), 0, 0, 0, Variant(structure=tuple(result['structure'])),
                    engine=engine)
    return task, genome_spec(task).encode(design)


def measure_bag(bag, tolerance, unseen_worlds, processes=1):
    """Return the measures record of a finished run's best design on its unseen worlds."""
    task, x, structure = records.final_design(bag)
    worlds = unseen_world_states(task, unseen_worlds)
    measures = measure_worlds(x, task, worlds, processes)
    return {'bag': str(bag), 'seed': task.seed, 'structure': list(structure),
            'unseen_worlds': unseen_worlds, 'worlds': world_measures_dict(measures),
            'summary': summarize(measures, tolerance).as_dict()}


def measure_structures(bags, tolerance, unseen_worlds, processes=1):
    """Return {structure text: measures record} of each structure's best design (a hierarchy)."""
    measured = {}
    for structure, (_, candidate_id, bag) in sorted(structure_bests(bags).items()):
        record = records.open_run(bag, warn=False)
        design = records.recorded_design(record, candidate_id)
        task = records.run_task_of(record, Variant(structure=tuple(structure)))
        measures = measure_worlds(design.x, task, unseen_world_states(task, unseen_worlds),
                                  processes)
        measured[structure_text(structure)] = {
            'candidate_id': candidate_id, 'worlds': world_measures_dict(measures),
            'summary': summarize(measures, tolerance).as_dict()}
    return measured


def structure_text(structure):
    """Return a structure as the paper writes it, e.g. '(1,3)'."""
    return '(' + ','.join(str(joints) for joints in structure) + ')'
