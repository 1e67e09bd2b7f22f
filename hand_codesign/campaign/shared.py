"""
Configurations and budgets that more than one experiment runs.

The paper's grid of Tasks 5 and 6 (two algorithms on 8, 64 and 128 worlds), the levers of the
search beyond the paper (restarts, the worst worlds, resampled worlds, quality diversity,
racing over the worlds) on one preset, the presets' own lever (a preset choice of ours
revisited), the fixed hand read with the palm beside the box, the palm's placement searched,
and the levers' budgets. A lever of one experiment alone lives in that experiment's module.
"""

from hand_codesign.campaign.experiment import Budget
from hand_codesign.campaign.experiment import Configuration

# training worlds per candidate of the levers' configurations (the reduced budget's 16)
LEVER_WORLDS = 16
# the levers of the worlds, as (dotted task key, value) options: each candidate scored on the
# worst quarter of its worlds (CVaR), and worlds drawn afresh each generation
WORST_QUARTER = (('worlds.aggregate', 'worst'), ('worlds.fraction', 0.25))
RESAMPLED = (('worlds.resample', 'generation'),)
# racing over the worlds (core.search.racing): 4 rounds, a world's weighted objectives within
# 2 cm of what a generation's candidates share on it; about the median span of a candidate's
# worlds so (bench/bench_racing.py: 0.009 on Task 5, 0.014 on Task 6), so the race can stop some
RACED = (('worlds.racing.rounds', 4), ('worlds.racing.range', 0.02))
# beyond Table I: five times Task 6's torque bound, the penalty's threshold at 80 % of it
FIVE_TIMES_TORQUE = (('policy.torque.bounds', (-0.05, 0.05)), ('torque_penalty.threshold', 0.04))


def joint_limit_configurations(preset, name, policies):
    """
    Return the paper's grid: CMA-ES and MO-CMA-ES on 8, 64 and 128 worlds, per policy.

    Args:
        preset: the torque policy's pinned preset (file name in config/reproduce/).
        name: the task's name; the PD policy's preset is `<name>_pd.yaml`.
        policies: ('torque',) or ('torque', 'pd').

    Returns:
        tuple of Configuration, keyed '<policy>-<algorithm>-<worlds>w'.
    """
    return tuple(
        Configuration(f'{policy}-{algorithm}-{worlds}w', policy_preset, algorithm, worlds,
                      policy)
        for policy, policy_preset in zip(policies, (preset, f'{name}_pd.yaml'))
        for algorithm in ('cma', 'mocma') for worlds in (8, 64, 128))


def lever_configurations(preset):
    """Return the paper's algorithms and each lever of the search beyond it, on one preset."""
    levers = (('cma', 'cma', ()), ('mocma', 'mocma', ()), ('ipop-cma', 'ipop-cma', ()),
              ('bipop-cma', 'bipop-cma', ()),
              ('cma-worst25', 'cma', WORST_QUARTER), ('cma-resample', 'cma', RESAMPLED),
              ('cma-worst25-resample', 'cma', WORST_QUARTER + RESAMPLED),
              ('cma-mae', 'cma-mae', ()), ('cma-raced', 'cma', RACED))
    return tuple(Configuration(key, preset, algorithm, LEVER_WORLDS, 'torque', options)
                 for key, algorithm, options in levers)


def preset_lever_configurations(preset, name):
    """
    Return a preset changed by the presets' lever, searched as the paper's preset.

    Plain CMA-ES, and the best levers on the paper's preset: resampled worlds and quality
    diversity; and IPOP-CMA-ES with a stagnation window of 10 generations, since with its
    default window (56 generations for their 24 genes and 40 candidates) no restart fires
    in 40. Last, CMA-MAE over the joint-limit span and the outcome limit_rest (the share of
    worlds in which the design ends on a joint limit while touching the box, core.outcomes):
    an archive that keeps the designs that find their joint limits apart from those that do
    not.
    """
    return (Configuration(f'cma-{name}', preset, 'cma', LEVER_WORLDS, 'torque'),
            Configuration(f'cma-{name}-resample', preset, 'cma', LEVER_WORLDS, 'torque',
                          (('worlds.resample', 'generation'),)),
            Configuration(f'cma-mae-{name}', preset, 'cma-mae', LEVER_WORLDS, 'torque'),
            Configuration(f'ipop-cma-{name}-stagnation-10', preset, 'ipop-cma', LEVER_WORLDS,
                          'torque', (('optimizer.restart_stagnation', 10),)),
            Configuration(f'cma-mae-limit-rest-{name}', preset, 'cma-mae', LEVER_WORLDS,
                          'torque',
                          (('optimizer.archive.descriptors', ('joint_range', 'limit_rest')),)))


def palm_beside_configuration(name):
    """
    Return CMA-ES on a task's fixed hand read the other way: the palm beside the box.

    Table I fixes Tasks 5 and 6's joint axes without saying which way they point. The pinned
    presets hang the palm above the box, the fingers swinging in a vertical plane; this
    one stands the palm upright beside the box, the fingers at its height swinging parallel
    to the table, so that segments held at their limits can form a wall in the plane, as in
    Figs. 4 and 5 (the reading is chosen on tuning seeds 1 to 3).
    """
    return Configuration('cma-palm-beside', f'{name}_palm_beside.yaml', 'cma', LEVER_WORLDS,
                         'torque')


def placement_options(position_bounds, yaw_bounds):
    """
    Return the options that search the palm's place and its turn about the vertical.

    Args:
        position_bounds: ((x lower, x upper), (y lower, y upper), (z lower, z upper)) of the
            palm centre in the world frame, m; a pair of equal values keeps that axis fixed.
        yaw_bounds: (lower, upper) of the hand's turn about the world vertical through the
            palm centre, rad, after the preset's base orientation.

    Returns:
        tuple of (dotted task key, value): hand.base_position and hand.base_yaw as bounds.
    """
    return (('hand.base_position', {'bounds': [list(pair) for pair in position_bounds]}),
            ('hand.base_yaw', {'bounds': list(yaw_bounds)}))


def lever_budgets(paper_worlds):
    """
    Return the levers' budgets: 40 x 40 on 16 worlds, and Table I's, each over 5 seeds.

    Args:
        paper_worlds: the training worlds of every configuration at the paper's budget.

    Returns:
        dict of 'smoke', 'reduced' and 'paper' to Budget.
    """
    return {'smoke': Budget('smoke', 4, 8, 100, 1, world_states=4),
            'reduced': Budget('reduced', 40, 40, 1000, 5, world_states=LEVER_WORLDS),
            'paper': Budget('paper', 100, 80, 1000, 5, world_states=paper_worlds)}
