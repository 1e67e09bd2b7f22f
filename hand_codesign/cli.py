"""
The `hand-codesign` command: check a task, run a co-design, then analyse, replay and export it.

Each verb lives in its own module and is imported only when used, so that `hand-codesign
analyze` works on a machine without a ROS installation and `--help` answers at once.
"""

import argparse
import importlib
import sys

from hand_codesign.errors import UserError

# verb -> (module, function, one-line help); the function takes the parsed arguments.
VERBS = {
    'check': ('hand_codesign.check', 'check_command',
              'validate a task file and show what a run of it would do, without simulating'),
    'run': ('hand_codesign.commands.run', 'run_command',
            'run a co-design as ROS 2 processes and record it to a bag'),
    'analyze': ('hand_codesign.analysis.report', 'analyze_command',
                'write plots, a CSV and a report of a run from its bag'),
    'replay': ('hand_codesign.analysis.replay', 'replay_command',
               're-simulate a recorded design, check its objectives, render it'),
    'robustness': ('hand_codesign.analysis.robustness_report', 'robustness_command',
                   'evaluate the best design of a bag on many world states'),
    'export': ('hand_codesign.analysis.export', 'export_command',
               'write the best design of a bag as URDF and its controller as YAML'),
}


def add_run_arguments(parser):
    parser.add_argument('--task', help='task file (YAML), e.g. config/tasks/task5.yaml')
    parser.add_argument('--evaluators', type=int, default=2,
                        help='evaluator processes to start (default 2; 0: wait for '
                             'evaluators started elsewhere)')
    parser.add_argument('--bag', help='where to write the bag (a new folder)')
    parser.add_argument('--seed', type=int, help="run seed (default: the task file's)")
    parser.add_argument('--iterations', type=int, help='generations per structure')
    parser.add_argument('--popsize', type=int, help='candidates per generation')
    parser.add_argument('--world-states', type=int, help='randomized worlds per candidate')
    parser.add_argument('--resume', metavar='BAG', help='continue the run recorded in BAG')
    parser.add_argument('--domain-id', type=int,
                        help='ROS_DOMAIN_ID of the run (default: a free one of this host)')
    parser.add_argument('--quiet', action='store_true', help='print only the final summary')
    parser.add_argument('--write-key-file', action='append', default=[], metavar='ID=PATH',
                        help='write the key of evaluator ID to PATH (mode 0600, outside the bag) '
                             'for an evaluator on another host: -p key_file:=PATH')
    parser.add_argument('--audit-fraction', type=float,
                        help='share of answers a second evaluator checks (default 0.1; 0: none)')


def add_check_arguments(parser):
    parser.add_argument('task', help='task file (YAML), e.g. config/tasks/task5.yaml')
    parser.add_argument('--json', action='store_true',
                        help='print one JSON object (floats exact) instead of the text')
    parser.add_argument('--seed', type=int, help="run seed (default: the task file's)")
    parser.add_argument('--iterations', type=int, help='generations per structure')
    parser.add_argument('--popsize', type=int, help='candidates per generation')
    parser.add_argument('--world-states', type=int, help='randomized worlds per candidate')


def add_bag_arguments(verb, parser):
    parser.add_argument('bag', help='bag of a run (folder or .mcap file)')
    if verb == 'analyze':
        parser.add_argument('--out', help='report folder (default: <bag>_report)')
    elif verb == 'replay':
        parser.add_argument('--generation', type=int, help='generation (default: the best)')
        parser.add_argument('--rank', type=int, default=0,
                            help='rank within the generation, 0 = best')
        parser.add_argument('--world', type=int, default=0, help='world state to replay')
        output = parser.add_mutually_exclusive_group()
        output.add_argument('--gif', help='write an animated GIF of the motion')
        output.add_argument('--gui', action='store_true', help='open the PyBullet window')
    elif verb == 'robustness':
        parser.add_argument('--samples', type=int, default=15625,
                            help='world states (default 15625 = 5 values on 6 quantities)')
        parser.add_argument('--out', help='output folder (default: <bag>_robustness)')
        parser.add_argument('--workers', type=int, help='processes (default: all cores)')
    elif verb == 'export':
        parser.add_argument('--out', required=True, help='folder for the URDF and YAML')


def build_parser():
    parser = argparse.ArgumentParser(
        prog='hand-codesign',
        description='Co-design robot hands and their control by evolution strategies.')
    verbs = parser.add_subparsers(dest='verb', metavar='VERB', required=True)
    for verb, (_, _, help_text) in VERBS.items():
        verb_parser = verbs.add_parser(verb, help=help_text, description=help_text)
        if verb == 'run':
            add_run_arguments(verb_parser)
        elif verb == 'check':
            add_check_arguments(verb_parser)
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
    arguments = build_parser().parse_args(argv)
    try:
        command = load_verb(arguments.verb)
        return command(arguments) or 0
    except UserError as error:
        print(f'hand-codesign {arguments.verb}: error: {error}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f'hand-codesign {arguments.verb}: interrupted', file=sys.stderr)
        return 130


if __name__ == '__main__':
    sys.exit(main())
