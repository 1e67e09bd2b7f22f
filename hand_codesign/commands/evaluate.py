"""
`hand-codesign evaluate BAG --rig`: test a run's best designs on a rig, beside their prediction.

Reads the run of BAG, takes its `--top` best designs (lowest fitness first) and starts the
processes of a re-evaluation (hand_codesign.ros.reevaluation_node): a recorder, one simulation
evaluator (the prediction), a rig evaluator (the measurement) and, with `--rig sim`, a
simulated rig; with `--rig hardware` the rig's own software joins the printed ROS domain. The
new bag holds both answers of every design and the measured pose traces; the command ends by
printing the gap between prediction and measurement, as `hand-codesign analyze` reports it.
"""

import pathlib
import tempfile

from hand_codesign.analysis.records import open_run
from hand_codesign.analysis.records import ranked_candidate_id
from hand_codesign.analysis.records import recorded_design
from hand_codesign.analysis.records import require_run_info
from hand_codesign.analysis.rig_report import rig_comparison
from hand_codesign.commands.run import rig_parameters
from hand_codesign.commands.run import run_domain
from hand_codesign.commands.run import termination_as_interrupt
from hand_codesign.core.rig.reevaluation import plan_text
from hand_codesign.errors import UserError
from hand_codesign.ros.runner import claimed_domain
from hand_codesign.ros.runner import System

NODE_MODULE = 'hand_codesign.ros.reevaluation_node'


def evaluate_command(arguments):
    """Re-evaluate a bag's best designs in simulation and on a rig; return the exit code."""
    if not arguments.rig:
        raise UserError('--rig: expected "hardware" (a test rig joins the ROS domain) or '
                        '"sim" (a simulated rig); evaluating without a rig is `replay`')
    if arguments.top < 1:
        raise UserError(f'--top {arguments.top}: expected at least 1 design')
    record = open_run(arguments.bag)
    run = require_run_info(record, 're-evaluating its designs')
    designs = []
    for rank in range(arguments.top):
        try:
            designs.append(recorded_design(record, ranked_candidate_id(record, rank=rank)))
        except UserError:
            if not designs:
                raise
            break
    out = pathlib.Path(arguments.out or f'{str(arguments.bag).rstrip("/")}_rig').resolve()
    if out.exists():
        raise UserError(f'--out {out}: already exists; choose a new path')
    requested, how = run_domain(arguments.domain_id)  # as `run`: the environment's by default
    with tempfile.TemporaryDirectory() as folder, claimed_domain(requested) as domain:
        plan = pathlib.Path(folder) / 'plan.json'
        plan.write_text(plan_text(run, designs), encoding='utf-8')
        system = System(out, domain)
        system.rig_parameters = rig_parameters(arguments)
        system.say(f'evaluate: {len(designs)} designs of run {run.run_id} in simulation and '
                   f'on the {arguments.rig} rig, ROS_DOMAIN_ID={domain} ({how}), bag {out}')
        try:
            with termination_as_interrupt():
                code = system.run(1, NODE_MODULE, {'plan_file': plan,
                                                   'timeout': float(arguments.timeout)},
                                  arguments.rig)
        except KeyboardInterrupt:
            system.stop_all()
            print(f'bag (interrupted): {out}')
            return 130
        finally:
            system.stop_all()
    print(f'bag: {out}')
    if code != 0:
        return code
    table = rig_comparison(open_run(out))
    print(table.text() if table is not None else 'no design has both answers', flush=True)
    return 0 if table is not None else 1
