"""
`hand-codesign export BAG --out DIR [--candidate ID]`: a design as URDF and its controller as YAML.

The design is the run's best, or with `--candidate` any candidate the bag records: another
elite of a quality-diversity archive (`analyze` lists them with their ids), a design of an
earlier generation.

DIR receives:

- `hand.urdf`: the hand (palm and capsule segments, joint origins, axes and limits, link
  friction), written by `core.sim.hand.hand_urdf` from the same link table the simulator builds.
  Standard URDF has no capsule (PyBullet reads one, yourdfpy and urdfdom do not), so each
  capsule is written as what it is, a cylinder and a sphere at each end (the very text a run
  publishes as robot_description: core.experiments.motion.design_urdf); the file loads in
  PyBullet, yourdfpy and other URDF tools (in PyBullet pass URDF_USE_IMPLICIT_CYLINDER, or it
  turns cylinders into meshes). URDF has no initial joint angles: they are in the YAML.
- `hand.xml`: the same hand on the ground as MJCF, as core.sim.mujoco_sim builds it for MuJoCo
  (capsules, limits, contact settings); its keyframe `initial` holds the initial angles.
- `controller.yaml`: everything to rebuild and re-simulate the design without the bag:
  `controller` (the policy as a person reads it: kind, timing, values per joint name,
  initial joint angles), `design` (hand and controller in physical units, in the format of a
  task's `seed_design`, so it can seed a new search), `task` (the task file's text and the
  run's seed, budget, world states and structure), `recorded` (the run's objectives of this
  design, the version of the task they were measured on: a sub-problem of growing horizon, a
  stage; and its normalized genome) and where it came from.

`load_export(DIR)` reads the folder back into an `Export`, and `resimulate(export)` evaluates
its design on its task; the command does that right away, on the version of the task the run
recorded the objectives on, and says whether they are the recorded ones (floats are written
with their exact shortest repr, so they round-trip).
"""

import dataclasses
import pathlib

from hand_codesign.analysis import records
from hand_codesign.core.design import Design
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.experiments.motion import design_urdf
from hand_codesign.core.run.runs import run_task
from hand_codesign.core.sim.hand import hand_model
from hand_codesign.core.task import parse_design
from hand_codesign.core.task import TaskError
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.core.task.variant import Variant
from hand_codesign.errors import UserError
from hand_codesign.outputs import staged
import numpy as np
import yaml

FORMAT = 'hand_codesign export 1'
URDF_NAME = 'hand.urdf'
MJCF_NAME = 'hand.xml'
YAML_NAME = 'controller.yaml'


def export_command(arguments):
    """Export a bag's best (or chosen) design; return 0, or 1 if re-simulating it differs."""
    record = records.open_run(arguments.bag)
    chosen = arguments.candidate
    if chosen is not None and chosen < 0:
        raise UserError(f'--candidate {chosen}: expected a candidate id of the bag (0 or more)')
    design = records.recorded_design(
        record, records.best_candidate_id(record) if chosen is None else chosen)
    out = pathlib.Path(arguments.out)
    with staged(out) as folder:
        paths = [out / path.name for path in export_design(record, design, folder)]
    print(f'exported candidate {design.candidate_id} of generation {design.generation} '
          f'(structure {list(design.structure)}): {paths[0]}, {paths[1]}')
    exported = load_export(out)
    evaluation = resimulate(exported, as_recorded=exported.objectives is not None)
    if exported.objectives is None:
        print('the bag holds no evaluation of this design; re-simulated objectives: '
              + _objective_text(exported.objective_names, evaluation.objectives))
        return 0
    same = np.array_equal(evaluation.objectives, exported.objectives)
    if same:
        print('re-simulating the exported files gives the recorded objectives'
              + _sub_problem_text(design) + ': '
              + _objective_text(exported.objective_names, evaluation.objectives))
        return 0
    print('EXPORT MISMATCH: re-simulating the exported files gives '
          + _objective_text(exported.objective_names, evaluation.objectives)
          + ', the run recorded '
          + _objective_text(exported.objective_names, exported.objectives))
    return 1


def _sub_problem_text(recorded):
    if recorded.horizon:
        return f' (on the sub-problem up to {recorded.horizon:g} s they were recorded on)'
    return ''


def _objective_text(names, values):
    return ', '.join(f'{name} {float(value)!r}' for name, value in zip(names, values))


# -------------------------------------------------------------------- writing

def _floats(values):
    return [float(value) for value in np.asarray(values, dtype=float).ravel()]


def design_document(design):
    """Return a Design as plain YAML data, in the format of a task's seed_design."""
    fingers = []
    for finger in design.hand.fingers:
        joints = []
        for joint in finger.joints:
            entry = {'axis_angle': float(joint.axis_angle),
                     'initial_angle': float(joint.initial_angle)}
            if joint.lower_limit is not None:
                entry['lower_limit'] = float(joint.lower_limit)
                entry['upper_limit'] = float(joint.upper_limit)
            joints.append(entry)
        fingers.append({'position': _floats(finger.position),
                        'segment_lengths': _floats(finger.segment_lengths),
                        'joints': joints})
    controller = design.controller
    document = {'kind': controller.kind,
                'values': [_floats(row) for row in np.asarray(controller.values, dtype=float)]}
    for gain in ('kp', 'kd'):
        if getattr(controller, gain) is not None:
            document[gain] = _floats(getattr(controller, gain))
    placement = {}
    if design.hand.base_position is not None:   # a searched palm placement
        placement = {'base_position': _floats(design.hand.base_position),
                     'base_yaw': float(design.hand.base_yaw)}
    return {'friction': float(design.hand.friction), **placement, 'fingers': fingers,
            'controller': document}


def controller_document(task, design, joint_names):
    """Return the controller as a person reads it: timing and values per joint name."""
    policy = task.policy
    controller = design.controller
    values = np.asarray(controller.values, dtype=float)
    document = {'kind': controller.kind, 'time_step': float(task.time_step),
                'duration': float(policy.duration),
                'gravity_compensation': bool(policy.gravity_compensation),
                'joints': list(joint_names)}
    if controller.kind == 'torque':
        document['mode'] = policy.mode
        document['unit'] = 'N m'
        document['torques'] = {name: _floats(values[:, index])
                               for index, name in enumerate(joint_names)}
    else:
        document['unit'] = 'rad'
        document['keyframe_times'] = _floats(policy.keyframe_times)
        document['targets'] = {name: _floats(values[:, index])
                               for index, name in enumerate(joint_names)}
        document['kp'] = dict(zip(joint_names, _floats(controller.kp)))
        document['kd'] = dict(zip(joint_names, _floats(controller.kd)))
    angles = [joint.initial_angle for finger in design.hand.fingers for joint in finger.joints]
    document['initial_angles'] = dict(zip(joint_names, _floats(angles)))
    return document


class _Literal(str):
    """A string dumped as a YAML block literal (the task file stays readable)."""


def _sub_problem_document(variant):
    """Return a Variant's coordinates besides its structure and worlds as plain YAML data."""
    return {'horizon': float(variant.horizon), 'stage': int(variant.stage),
            'held_out': bool(variant.held_out), 'world_draw': int(variant.world_draw)}


def _literal(dumper, text):
    return dumper.represent_scalar('tag:yaml.org,2002:str', text, style='|')


class _Dumper(yaml.SafeDumper):
    pass


_Dumper.add_representer(_Literal, _literal)


def export_design(record, recorded, out):
    """Write hand.urdf, hand.xml, controller.yaml of a RecordedDesign; return (urdf, yaml)."""
    task = records.design_task(record, recorded)
    design = genome_spec(task).decode(recorded.x)
    model = hand_model(design.hand, task.hand)
    joint_names = [link.joint_name for link in model.links]
    info = record.run_info
    document = {
        'format': FORMAT,
        'source': {'bag': str(pathlib.Path(record.path).resolve()), 'run_id': record.run_id,
                   'candidate_id': recorded.candidate_id, 'generation': recorded.generation,
                   'versions': list(info.versions)},
        'urdf': URDF_NAME,
        'controller': controller_document(task, design, joint_names),
        'design': design_document(design),
        # its engines, comma-separated as RunInfo.engine (core.run.runs): 'pybullet,mujoco'
        'task': {'name': task.name, 'engine': ','.join(task.physics.engines),
                 'seed': int(task.seed), 'iterations': task.iterations,
                 'population': task.population, 'world_states': task.num_world_states,
                 'structure': [int(joints) for joints in task.structure],
                 # lines ending in spaces cannot be block literals; a rare task file has them
                 'yaml': (_Literal(info.task_yaml) if not any(
                     line != line.rstrip() for line in info.task_yaml.splitlines())
                     else info.task_yaml)},
        'recorded': {
            'objectives': (None if recorded.objectives is None else
                           dict(zip(recorded.objective_names, _floats(recorded.objectives)))),
            'fitness': None if recorded.fitness is None else float(recorded.fitness),
            'genome': dict(zip(recorded.genome_names, _floats(recorded.x))),
            # the version of the task they were measured on: a sub-problem of growing horizon
            # (s, 0 the whole motion), a stage of a two-stage task, a draw of the worlds
            'evaluated_on': _sub_problem_document(recorded.variant),
        },
    }
    try:
        out.mkdir(parents=True, exist_ok=True)
        urdf_path = out / URDF_NAME
        name = f'{task.name}_candidate{recorded.candidate_id}'
        urdf_path.write_text(design_urdf(task, design, name), encoding='utf-8')
        from hand_codesign.core.sim.mujoco_sim import model_mjcf  # see core.evaluate.new_simulator
        (out / MJCF_NAME).write_text(model_mjcf(
            model, task.time_step, model.base_position, model.base_orientation,
            task.policy.gravity_compensation, name), encoding='utf-8')
        yaml_path = out / YAML_NAME
        header = (f'# {task.name}: candidate {recorded.candidate_id} of run {record.run_id}, '
                  f'exported by hand-codesign export.\n# The hand is {URDF_NAME}; values are '
                  'SI (m, rad, N m, s). load with hand_codesign.analysis.export.load_export.\n')
        yaml_path.write_text(header + yaml.dump(document, Dumper=_Dumper, sort_keys=False,
                                                allow_unicode=True, width=99),
                             encoding='utf-8')
    except OSError as error:
        raise UserError(f'--out {out}: cannot write the export: {error}') from None
    return urdf_path, yaml_path


# -------------------------------------------------------------------- reading

@dataclasses.dataclass
class Export:
    """An exported design read back: its task, Design and what the run recorded."""

    path: pathlib.Path
    task: object                # the run's task, whole motions
    recorded_task: object       # the version of it the objectives were recorded on
    design: Design
    urdf_path: pathlib.Path
    objective_names: list
    objectives: np.ndarray      # None when the run recorded none
    fitness: float
    document: dict


class _Fields:
    """Reads a YAML mapping, naming the file and key of anything missing or malformed."""

    def __init__(self, path):
        self.path = path

    def fail(self, key, expected):
        raise UserError(f'{self.path}: {key}: expected {expected}')

    def mapping(self, value, key):
        if not isinstance(value, dict):
            self.fail(key, 'a mapping')
        return value

    def get(self, mapping, name, key):
        if name not in mapping:
            self.fail(f'{key}.{name}' if key else name, 'this key')
        return mapping[name]

    def number(self, value, key):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f'a number, got {value!r}')
        return float(value)


def load_export(folder):
    """Return the Export in folder (written by `hand-codesign export`)."""
    folder = pathlib.Path(folder)
    path = folder / YAML_NAME if folder.is_dir() else folder
    try:
        document = yaml.safe_load(path.read_text(encoding='utf-8'))
    except OSError as error:
        raise UserError(f'{path}: cannot read the export: {error.strerror}') from None
    except yaml.YAMLError as error:
        raise UserError(f'{path}: not valid YAML: {error}') from None
    fields = _Fields(path)
    document = fields.mapping(document, '(top level)')
    if document.get('format') != FORMAT:
        fields.fail('format', f'{FORMAT!r} (a file written by hand-codesign export), got '
                              f'{document.get("format")!r}')
    task_document = fields.mapping(fields.get(document, 'task', ''), 'task')
    try:
        task = run_task(str(fields.get(task_document, 'yaml', 'task')), f'{path} (task.yaml)',
                        int(fields.get(task_document, 'seed', 'task')),
                        int(task_document.get('iterations') or 0),
                        int(task_document.get('population') or 0),
                        int(task_document.get('world_states') or 0),
                        Variant(structure=tuple(task_document.get('structure') or ())),
                        engine=str(task_document.get('engine') or ''))
    except (TaskError, ValueError, TypeError) as error:
        raise UserError(f'{path}: task: cannot rebuild the task: {error}') from None
    try:
        design = parse_design(fields.get(document, 'design', ''), str(path))
    except TaskError as error:
        raise UserError(str(error)) from None
    if design.hand.structure != tuple(task.structure):
        fields.fail('design.fingers', f'the structure of the task, {list(task.structure)}, got '
                                      f'{list(design.hand.structure)}')
    recorded = fields.mapping(document.get('recorded') or {}, 'recorded')
    objectives = recorded.get('objectives')
    names = list(task.objective_names)
    values = None
    if objectives:
        objectives = fields.mapping(objectives, 'recorded.objectives')
        values = np.array([fields.number(fields.get(objectives, name, 'recorded.objectives'),
                                         f'recorded.objectives.{name}') for name in names])
    fitness = recorded.get('fitness')
    evaluated_on = fields.mapping(recorded.get('evaluated_on') or {}, 'recorded.evaluated_on')
    try:
        sub_problem = Variant(horizon=float(evaluated_on.get('horizon', 0.0)),
                              stage=int(evaluated_on.get('stage', 0)),
                              held_out=bool(evaluated_on.get('held_out', False)),
                              world_draw=int(evaluated_on.get('world_draw', 0)))
    except (TypeError, ValueError):
        fields.fail('recorded.evaluated_on', 'numbers horizon (s), stage, world_draw and a '
                                             f'boolean held_out, got {evaluated_on!r}')
    return Export(path=path, task=task, design=design, recorded_task=task.replace(
                      **sub_problem.task_changes()),
                  urdf_path=path.parent / str(document.get('urdf', URDF_NAME)),
                  objective_names=names, objectives=values,
                  fitness=None if fitness is None else float(fitness), document=document)


def resimulate(exported, worlds=None, as_recorded=False):
    """
    Return the core Evaluation of an Export's design on its task (default: its worlds).

    as_recorded: on the version of the task the run recorded its objectives on (a sub-problem
    of growing horizon, a stage), to compare with them; else on the task's whole motions.
    """
    task = exported.recorded_task if as_recorded else exported.task
    try:
        return evaluate_design(exported.design, task, worlds)
    except ValueError as error:
        raise UserError(f'{exported.path}: the design cannot be simulated: {error}') from None
