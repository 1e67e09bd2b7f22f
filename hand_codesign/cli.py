"""
The `hand-codesign` command: check a task, run a co-design, then analyse, replay and export it.

Each verb lives in its own module and is imported only when used, so that `hand-codesign
analyze` works on a machine without a ROS installation and `--help` answers at once.
"""

import argparse
import importlib
import sys

from hand_codesign.deprecation import show_old_names, warn_old_name
from hand_codesign.errors import closed_stdout_status, UserError
from hand_codesign.version import version_text

ENGINE_NAMES = ('pybullet', 'mujoco')  # core.task.parts.ENGINES (cli imports no core module)

# verb -> (module, function, one-line help); the function takes the parsed arguments.
VERBS = {
    'check': ('hand_codesign.commands.check', 'check_command',
              'validate a task file and show what a run of it would do, without simulating'),
    'run': ('hand_codesign.commands.run', 'run_command',
            'run a co-design as ROS 2 processes and record it to a bag'),
    'analyze': ('hand_codesign.analysis.report', 'analyze_command',
                'write plots, a CSV and a report of a run from its bag'),
    'replay': ('hand_codesign.commands.replay', 'replay_command',
               're-simulate a recorded design, check its objectives, render it'),
    'robustness': ('hand_codesign.analysis.robustness_report', 'robustness_command',
                   'evaluate the best design of a bag on many world states'),
    'export': ('hand_codesign.analysis.export', 'export_command',
               'write the best design of a bag as URDF and its controller as YAML'),
    'evaluate': ('hand_codesign.commands.evaluate', 'evaluate_command',
                 "test a bag's best designs on a rig, beside their simulated prediction"),
    'recover': ('hand_codesign.commands.recover', 'recover_command',
                'close the bag of a recorder that was killed, so that any reader takes it'),
    'reproduce': ('hand_codesign.commands.reproduce', 'reproduce_command',
                  "run one of the paper's experiments and write its tables and figures"),
    'offsets': ('hand_codesign.analysis.offsets', 'offsets_command',
                "where a run's best design leaves the object, along each axis of the plane"),
    'transfer': ('hand_codesign.analysis.transfer', 'transfer_command',
                 'tabulate designs measured in both physics engines (analyze --unseen)'),
}
# verb -> an example of it, shown at the end of its --help (test_cli parses each)
EXAMPLES = {
    'check': 'hand-codesign check config/tasks/task5.yaml --population 16',
    'run': 'hand-codesign run --task config/tasks/task5.yaml --evaluators 2 --bag bags/my-run \\\n'
           '      --seed 1 --iterations 30 --population 16 --world-states 16',
    'analyze': 'hand-codesign analyze bags/my-run --unseen 1000 --format svg',
    'replay': 'hand-codesign replay bags/my-run --gif bags/my-run.gif',
    'robustness': 'hand-codesign robustness bags/my-run --samples 729',
    'export': 'hand-codesign export bags/my-run --out bags/my-run-hand',
    'evaluate': 'hand-codesign evaluate bags/my-run --rig sim --top 3',
    'recover': 'hand-codesign recover bags/my-run',
    'reproduce': 'hand-codesign reproduce task5-joint-limits --budget smoke --seeds 2',
    'offsets': 'hand-codesign offsets bags/my-run --unseen 1000 --table bags/my-run-offsets',
    'transfer': "hand-codesign transfer docs/results/task5-transfer --title 'Task 5 in both "
                "engines'",
}
DOMAIN_HELP = ("ROS_DOMAIN_ID (default: the environment's, as ROS 2 tools; 0 if unset); auto: "
               'a free one of this host')
DEFAULT_PORT = 11811   # Fast DDS's own default for a discovery server
MAX_DOMAIN_ID = 232    # ros.runner's; not imported from there, so that --help needs no ROS


def camera_view(text):
    """Return (yaw, pitch) in degrees of a --camera value 'YAW,PITCH'."""
    try:
        yaw, pitch = (float(part) for part in text.split(','))
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected YAW,PITCH in degrees, e.g. 0,60; got {text!r}')
    if not -90 < pitch < 90:
        raise argparse.ArgumentTypeError(f'the pitch must lie between -90 and 90 degrees, got '
                                         f'{pitch:g}')
    return yaw, pitch


def domain_id_option(text):
    """Return --domain-id's value: 'auto', or a ROS domain id (0 to 232)."""
    if text == 'auto':
        return text
    if not text.isdigit() or int(text) > MAX_DOMAIN_ID:
        raise argparse.ArgumentTypeError(f'expected "auto" or 0 to {MAX_DOMAIN_ID}, got {text!r}')
    return int(text)


def engines_option(text):
    """Return --engine's value: an engine, or several comma-separated (pybullet,mujoco)."""
    names = text.split(',')
    if not names or any(name not in ENGINE_NAMES for name in names) \
            or len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(
            f'expected {" or ".join(ENGINE_NAMES)}, or several comma-separated, e.g. '
            f'{",".join(ENGINE_NAMES)}; got {text!r}')
    return text


def seconds_option(text):
    """Return a duration option's value: seconds, a number of at least 0."""
    try:
        seconds = float(text)
    except ValueError:
        seconds = -1.0
    if not seconds >= 0.0:
        raise argparse.ArgumentTypeError(f'expected seconds (a number >= 0), got {text!r}')
    return seconds


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Help that shows each option's default, unless its text already says it."""

    def _get_help_string(self, action):
        text = action.help or ''
        if ('default' in text or not action.option_strings or action.required
                or any(action.default is nothing for nothing in (None, False, argparse.SUPPRESS))
                or action.default == []):
            return text
        return f'{text} (default %(default)s)'


class OldOption(argparse.Action):
    """An option's old name (hand_codesign.deprecation): read as the new one, with a line."""

    def __init__(self, option_strings, dest, new, **keywords):
        super().__init__(option_strings, dest, help=argparse.SUPPRESS, **keywords)
        self.new = new

    def __call__(self, parser, namespace, values, option_string=None):
        warn_old_name(option_string, self.new)
        setattr(namespace, self.dest, values)


def add_budget_arguments(parser):
    """Add the seed and budget options `run` and `check` share."""
    parser.add_argument('--seed', type=int, help="run seed (default: the task file's)")
    parser.add_argument('--iterations', type=int,
                        help="generations per structure (default: the task file's "
                             'optimizer.iterations)')
    parser.add_argument('--population', type=int,
                        help="candidates per generation (default: the task file's "
                             'optimizer.population)')
    parser.add_argument('--popsize', dest='population', type=int, action=OldOption,
                        new='--population')
    parser.add_argument('--world-states', type=int,
                        help="randomized worlds per candidate (default: the task file's "
                             'world_states)')


def add_run_arguments(parser):
    parser.add_argument('--task', help='task file (YAML), e.g. config/tasks/task5.yaml '
                                       '(required unless --resume; no default)')
    parser.add_argument('--evaluators', type=int, default=2,
                        help='evaluator processes to start (default 2; 0: wait for '
                             'evaluators started elsewhere)')
    parser.add_argument('--bag', help='where to write the bag, a new folder (default '
                                      'bags/<task>-<date>-<time>)')
    add_budget_arguments(parser)
    parser.add_argument('--engine', type=engines_option, metavar='ENGINE[,ENGINE]',
                        help='physics engine, or engines every candidate meets the same worlds '
                             "in, e.g. pybullet,mujoco (default: the task file's physics)")
    parser.add_argument('--resume', metavar='BAG',
                        help='continue the run recorded in BAG (with --iterations N: a '
                             'finished one, on to N generations; default: a new run)')
    parser.add_argument('--domain-id', type=domain_id_option, metavar='ID|auto',
                        help=DOMAIN_HELP)
    parser.add_argument('--quiet', action='store_true', help='print only the final summary')
    parser.add_argument('--progress-every', type=seconds_option, metavar='SECONDS',
                        help="with --quiet, still print a generation's progress line, at most "
                             'one every SECONDS (default: none; reproduce: 300)')
    parser.add_argument('--discovery-server', type=int, nargs='?', const=DEFAULT_PORT,
                        metavar='PORT',
                        help='start a Fast DDS discovery server (UDP port, default '
                             f'{DEFAULT_PORT}) for evaluators on hosts without multicast; '
                             'prints how they join (default: none, multicast discovery)')
    parser.add_argument('--start-timeout', type=seconds_option, metavar='SECONDS',
                        help='seconds the evaluators have to join before the run gives up '
                             '(default 300 with --evaluators N > 0; 0: wait without limit, '
                             'the default with --evaluators 0)')
    parser.add_argument('--live', type=int, nargs='?', const=8765, metavar='PORT',
                        help='serve the run live to Foxglove over WebSocket (default: no live '
                             'view; PORT default 8765; 0: any free port)')
    parser.add_argument('--live-host', default='127.0.0.1', metavar='HOST',
                        help='address the live view serves on (default 127.0.0.1: this host '
                             'only)')
    parser.add_argument('--write-key-file', action='append', default=[], metavar='ID=PATH',
                        help='write the key of evaluator ID to PATH (mode 0600, outside the bag) '
                             'for an evaluator on another host: -p key_file:=PATH (default: '
                             'none)')
    parser.add_argument('--audit-fraction', type=float,
                        help='share of answers a second evaluator checks (default 0.1; 0: none)')
    add_rig_arguments(parser)


def add_rig_arguments(parser):
    parser.add_argument('--rig', choices=('hardware', 'sim'), default='',
                        help='also start a rig evaluator: "hardware" for a test rig that joins '
                             'the ROS domain, "sim" with a simulated rig (docs/RIG.md; default: '
                             'none)')
    parser.add_argument('--rig-rate', type=float, default=0.0,
                        help='--rig sim: poses per second (default 0: every physics step)')
    parser.add_argument('--rig-phase', type=float, default=0.0,
                        help='--rig sim: offset of the pose clock, in sample periods')
    parser.add_argument('--rig-engine', choices=('pybullet', 'mujoco'),
                        help="--rig sim: the rig's physics engine (default: the run's)")


def add_check_arguments(parser):
    parser.add_argument('task', help='task file (YAML), e.g. config/tasks/task5.yaml')
    parser.add_argument('--json', action='store_true',
                        help='print one JSON object (floats exact) instead of the text')
    add_budget_arguments(parser)


def add_reproduce_arguments(parser):
    parser.add_argument('experiment', nargs='?',
                        help='experiment name (see --list), or "all"')
    parser.add_argument('--list', action='store_true',
                        help='list the experiments, one a line, its name first')
    parser.add_argument('--budget', choices=('smoke', 'reduced', 'paper'), default='reduced',
                        help='smoke (minutes), reduced (about an hour per experiment on 2 '
                             "cores) or paper (Table I's); default reduced")
    parser.add_argument('--seeds',
                        help='the seeds of every configuration: N for 1 to N (N up to 20), A-B, '
                             "or A,B,... (default: the budget's, from 1)")
    parser.add_argument('--evaluators', type=int, default=2,
                        help='evaluator processes per run (default 2)')
    parser.add_argument('--out', help='campaign folder (default results/EXPERIMENT-BUDGET); '
                                      'give the same folder again to continue')
    parser.add_argument('--only', nargs='+', metavar='CONFIGURATION',
                        help="run only these of the experiment's configurations (the first "
                             'column of its table; default: all); the tables show every one '
                             'measured')
    parser.add_argument('--format', choices=('png', 'svg', 'pdf'), default='png',
                        help='file format of the figures (default png)')
    read_back = parser.add_mutually_exclusive_group()
    read_back.add_argument('--bands', type=float, nargs='+', metavar='EDGE',
                           help="don't run: print the share within per band of --quantity "
                                "of the campaign's unseen worlds, pooled over --seeds (the "
                                "budget's by default), e.g. --bands 0.5 0.75 1 1.5 2")
    read_back.add_argument('--rates', nargs='?', const='paper', metavar='BUDGET',
                           help="don't run: print the physics steps per second of the "
                                "campaign's runs and the time BUDGET would take (default "
                                'paper) here and on --hosts')
    parser.add_argument('--quantity', default='scale',
                        help='--bands: position_x, position_y, orientation, friction, scale '
                             '(default), mass or turn_friction (friction x mass x scale)')
    parser.add_argument('--cores', type=int, default=2, help='--rates: cores of this machine')
    parser.add_argument('--hosts', type=int, default=4, help='--rates: hosts to estimate for')
    parser.add_argument('--host-cores', type=int, default=8, help='--rates: cores per host')


def add_offsets_arguments(parser):
    parser.add_argument('bags', nargs='+', metavar='BAG', help='bags of finished runs')
    parser.add_argument('--unseen', type=int, default=1000, help='unseen worlds')
    parser.add_argument('--training', action='store_true',
                        help="also measure on the run's own training worlds")
    parser.add_argument('--table', metavar='OUT',
                        help='write OUT.csv and OUT.md (default: print the table only)')


def add_transfer_arguments(parser):
    parser.add_argument('folder', help='folder of RUN-in-pybullet.json and RUN-in-mujoco.json, '
                                       'written by `analyze BAG --unseen N --engine ENGINE`')
    parser.add_argument('--title', required=True, help="the table's title")
    parser.add_argument('--note', default='',
                        help='a paragraph under the title (default: none)')
    parser.add_argument('--measures', nargs='*', default=[], metavar='DIR',
                        help="a reproduce campaign's measures/ folder, for runs measured in "
                             'MuJoCo only (default: none)')


def add_bag_arguments(verb, parser):
    parser.add_argument('bag', help='bag of a run (folder or .mcap file)')
    if verb == 'analyze':
        parser.add_argument('--out', help='report folder (default: <bag>_report)')
        parser.add_argument('--unseen', type=int, default=0, metavar='N',
                            help='also measure the best design on N worlds it never trained '
                                 'on, as `reproduce` does (e.g. 1000; default: skip)')
        parser.add_argument('--engine', choices=('pybullet', 'mujoco'),
                            help='with --unseen: the physics engine to measure in '
                                 "(default: the run's)")
        parser.add_argument('--format', choices=('png', 'svg', 'pdf'), default='png',
                            help='file format of the figures (default png)')
    elif verb == 'replay':
        parser.add_argument('--generation', type=int,
                            help="generation (default: the run's best design's)")
        parser.add_argument('--rank', type=int, default=0,
                            help='rank within the generation, 0 = best')
        parser.add_argument('--candidate', type=int, metavar='ID',
                            help='the design of this candidate id instead (e.g. a design of '
                                 'the final front; not with --generation or --rank; default: '
                                 'none)')
        parser.add_argument('--world', type=int, default=0, help='world state to replay')
        output = parser.add_mutually_exclusive_group()
        output.add_argument('--gif', help='write an animated GIF of the motion (default: none)')
        output.add_argument('--gui', action='store_true', help='open the PyBullet window')
        parser.add_argument('--camera', type=camera_view, metavar='YAW,PITCH',
                            help="the animation's camera angles in degrees (default 0,-20: "
                                 'from the side, a little above; 0,60 looks up through the '
                                 'table at a hand above an object)')
        output.add_argument('--mcap', metavar='FILE',
                            help='write the rollout as a ROS 2 MCAP of markers (Foxglove; '
                                 'default: none)')
    elif verb == 'robustness':
        parser.add_argument('--samples', type=int, default=15625,
                            help='world states (default 15625 = 5 values on 6 quantities)')
        parser.add_argument('--out', help='output folder (default: <bag>_robustness)')
        parser.add_argument('--workers', type=int, help='processes (default: all cores)')
    elif verb == 'export':
        parser.add_argument('--out', required=True, help='folder for the URDF and YAML')
        parser.add_argument('--candidate', type=int, metavar='ID',
                            help="a recorded candidate's id instead of the best design, e.g. "
                                 'an elite of the archive `analyze` lists (default: the best)')
    elif verb == 'evaluate':
        parser.add_argument('--top', type=int, default=3,
                            help='how many of the best designs (default 3)')
        parser.add_argument('--out', help='bag of the re-evaluation (default: <bag>_rig)')
        parser.add_argument('--timeout', type=float, default=3600.0,
                            help='seconds to wait for every answer (default 3600)')
        parser.add_argument('--domain-id', type=domain_id_option, metavar='ID|auto',
                            help=DOMAIN_HELP)
        add_rig_arguments(parser)


class VersionAction(argparse.Action):
    """--version: print the package version (and the commit of a checkout) and exit."""

    def __init__(self, option_strings, dest, **keywords):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help='print the version (and the git commit of a checkout) and exit')

    def __call__(self, parser, namespace, values, option_string=None):
        print(f'hand-codesign {version_text()}')
        parser.exit()


def build_parser():
    parser = argparse.ArgumentParser(
        prog='hand-codesign',
        description='Co-design robot hands and their control by evolution strategies.')
    parser.add_argument('--version', action=VersionAction)
    verbs = parser.add_subparsers(dest='verb', metavar='VERB', required=True)
    for verb, (_, _, help_text) in VERBS.items():
        verb_parser = verbs.add_parser(verb, help=help_text, description=help_text,
                                       formatter_class=HelpFormatter,
                                       epilog=f'example:\n  {EXAMPLES[verb]}')
        if verb == 'run':
            add_run_arguments(verb_parser)
        elif verb == 'check':
            add_check_arguments(verb_parser)
        elif verb == 'reproduce':
            add_reproduce_arguments(verb_parser)
        elif verb == 'offsets':
            add_offsets_arguments(verb_parser)
        elif verb == 'transfer':
            add_transfer_arguments(verb_parser)
        else:
            add_bag_arguments(verb, verb_parser)
    return parser


def load_verb(verb):
    """Return the function implementing a verb, or raise UserError if it is not built yet."""
    module_name, function_name, _ = VERBS[verb]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name != module_name:
            raise
        raise UserError(f'the verb "{verb}" is not available in this version yet')
    return getattr(module, function_name)


def main(argv=None):
    show_old_names(lambda text: print(f'hand-codesign: {text}', file=sys.stderr))
    arguments = build_parser().parse_args(argv)
    try:
        command = load_verb(arguments.verb)
        status = command(arguments) or 0
        sys.stdout.flush()  # here, not at exit, where a reader gone would not be caught
        return status
    except UserError as error:
        print(f'hand-codesign {arguments.verb}: error: {error}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f'hand-codesign {arguments.verb}: interrupted', file=sys.stderr)
        return 130
    except BrokenPipeError as error:  # `hand-codesign ... | head`
        return closed_stdout_status(error)


if __name__ == '__main__':
    sys.exit(main())
