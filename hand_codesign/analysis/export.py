"""
`hand-codesign export BAG --out DIR`: the best design as URDF and its controller as YAML.

DIR receives:

- `hand.urdf`: the hand (palm and capsule segments, joint origins, axes and limits, link
  friction), written by `core.hand.hand_urdf` from the same link table the simulator builds.
  Standard URDF has no capsule (PyBullet reads one, yourdfpy and urdfdom do not), so each
  capsule is written as what it is, a cylinder and a sphere at each end; the file loads in
  PyBullet, yourdfpy and other URDF tools (in PyBullet pass URDF_USE_IMPLICIT_CYLINDER, or it
  turns cylinders into meshes). URDF has no initial joint angles: they are in the YAML.
- `controller.yaml`: everything to rebuild and re-simulate the design without the bag:
  `controller` (the policy as a person reads it: kind, timing, values per joint name,
  initial joint angles), `design` (hand and controller in physical units, in the format of a
  task's `seed_design`, so it can seed a new search), `task` (the task file's text and the
  run's seed, budget, world states and structure), `recorded` (the run's objectives of this
  design and its normalized genome) and where it came from.

`load_export(DIR)` reads the folder back into an `Export`, and `resimulate(export)` evaluates
its design on its task; the command does that right away and says whether the objectives are
the recorded ones (floats are written with their exact shortest repr, so they round-trip).
"""

import dataclasses
import math
import pathlib
import xml.etree.ElementTree as ElementTree

from hand_codesign.analysis import records
from hand_codesign.core.design import ControllerDesign
from hand_codesign.core.design import Design
from hand_codesign.core.design import FingerDesign
from hand_codesign.core.design import HandDesign
from hand_codesign.core.design import JointDesign
from hand_codesign.core.evaluate import evaluate_design
from hand_codesign.core.genome import genome_spec
from hand_codesign.core.hand import hand_model
from hand_codesign.core.hand import hand_urdf
from hand_codesign.core.runs import run_task
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
import numpy as np
import yaml

FORMAT = 'hand_codesign export 1'
URDF_NAME = 'hand.urdf'
YAML_NAME = 'controller.yaml'


def export_command(arguments):
    """Export the best design of a bag; return 0, or 1 if re-simulating it differs."""
    record = records.open_run(arguments.bag)
    design = records.recorded_design(record, records.best_candidate_id(record))
    out = pathlib.Path(arguments.out)
    paths = export_design(record, design, out)
    print(f'exported candidate {design.candidate_id} of generation {design.generation} '
          f'(structure {list(design.structure)}): {paths[0]}, {paths[1]}')
    exported = load_export(out)
    evaluation = resimulate(exported)
    if exported.objectives is None:
        print('the bag holds no evaluation of this design; re-simulated objectives: '
              + _objective_text(exported.objective_names, evaluation.objectives))
        return 0
    same = np.array_equal(evaluation.objectives, exported.objectives)
    if same:
        print('re-simulating the exported files gives the recorded objectives: '
              + _objective_text(exported.objective_names, evaluation.objectives))
        return 0
    print('EXPORT MISMATCH: re-simulating the exported files gives '
          + _objective_text(exported.objective_names, evaluation.objectives)
          + ', the run recorded '
          + _objective_text(exported.objective_names, exported.objectives))
    return 1


def _objective_text(names, values):
    return ', '.join(f'{name} {float(value)!r}' for name, value in zip(names, values))


# -------------------------------------------------------------------- writing

def _rpy_z_axis(rpy):
    """Return where the z axis of a frame turned by URDF roll, pitch, yaw points."""
    roll, pitch, yaw = rpy
    # third column of Rz(yaw) Ry(pitch) Rx(roll)
    return (math.cos(yaw) * math.sin(pitch) * math.cos(roll) + math.sin(yaw) * math.sin(roll),
            math.sin(yaw) * math.sin(pitch) * math.cos(roll) - math.cos(yaw) * math.sin(roll),
            math.cos(pitch) * math.cos(roll))


def _vector_text(values):
    return ' '.join(repr(float(value)) for value in values)


def standard_urdf(urdf_text):
    """
    Return URDF text with every capsule replaced by a cylinder and two end spheres.

    The three shapes cover exactly the capsule's volume, in elements of standard URDF.
    """
    robot = ElementTree.fromstring(urdf_text)
    for link in robot.iter('link'):
        for element in list(link):
            capsule = element.find('geometry/capsule')
            if element.tag not in ('visual', 'collision') or capsule is None:
                continue
            origin = element.find('origin')
            xyz = [float(v) for v in (origin.get('xyz', '0 0 0') if origin is not None
                                      else '0 0 0').split()]
            rpy = [float(v) for v in (origin.get('rpy', '0 0 0') if origin is not None
                                      else '0 0 0').split()]
            radius = capsule.get('radius')
            length = float(capsule.get('length'))
            axis = _rpy_z_axis(rpy)
            position = list(link).index(element)
            link.remove(element)
            shapes = [('cylinder', {'radius': radius, 'length': repr(length)}, xyz, rpy)]
            for sign in (-1.0, 1.0):
                # rounding noise of the turned axis (1e-18) would print as a real offset
                centre = [c + sign * length / 2 * (a if abs(a) > 1e-12 else 0.0)
                          for c, a in zip(xyz, axis)]
                shapes.append(('sphere', {'radius': radius}, centre, (0.0, 0.0, 0.0)))
            for offset, (tag, attributes, centre, turn) in enumerate(shapes):
                part = ElementTree.Element(element.tag)
                ElementTree.SubElement(part, 'origin', xyz=_vector_text(centre),
                                       rpy=_vector_text(turn))
                geometry = ElementTree.SubElement(part, 'geometry')
                ElementTree.SubElement(geometry, tag, attributes)
                link.insert(position + offset, part)
    ElementTree.indent(robot, space='  ')
    return '<?xml version="1.0"?>\n' + ElementTree.tostring(robot, encoding='unicode') + '\n'


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
    return {'friction': float(design.hand.friction), 'fingers': fingers,
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


def _literal(dumper, text):
    return dumper.represent_scalar('tag:yaml.org,2002:str', text, style='|')


class _Dumper(yaml.SafeDumper):
    pass


_Dumper.add_representer(_Literal, _literal)


def export_design(record, recorded, out):
    """Write hand.urdf and controller.yaml of a RecordedDesign into out; return both paths."""
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
        'task': {'name': task.name, 'seed': int(task.seed), 'iterations': task.iterations,
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
        },
    }
    try:
        out.mkdir(parents=True, exist_ok=True)
        urdf_path = out / URDF_NAME
        urdf_path.write_text(standard_urdf(hand_urdf(
            design.hand, task.hand, name=f'{task.name}_candidate{recorded.candidate_id}')),
            encoding='utf-8')
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
    task: object
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

    def numbers(self, value, key, count=None):
        if not isinstance(value, list) or (count is not None and len(value) != count):
            self.fail(key, f'a list of {count or "some"} numbers, got {value!r}')
        return tuple(self.number(item, f'{key}[{index}]') for index, item in enumerate(value))


def design_from_document(document, fields, key='design'):
    """Return the Design of design_document() data."""
    document = fields.mapping(document, key)
    fingers = []
    finger_list = fields.get(document, 'fingers', key)
    if not isinstance(finger_list, list) or not finger_list:
        fields.fail(f'{key}.fingers', 'a non-empty list of fingers')
    for index, finger in enumerate(finger_list):
        finger_key = f'{key}.fingers[{index}]'
        finger = fields.mapping(finger, finger_key)
        joints = []
        for joint_index, joint in enumerate(fields.get(finger, 'joints', finger_key)):
            joint_key = f'{finger_key}.joints[{joint_index}]'
            joint = fields.mapping(joint, joint_key)
            limits = (None, None)
            if 'lower_limit' in joint:
                limits = (fields.number(joint['lower_limit'], f'{joint_key}.lower_limit'),
                          fields.number(fields.get(joint, 'upper_limit', joint_key),
                                        f'{joint_key}.upper_limit'))
            joints.append(JointDesign(
                axis_angle=fields.number(fields.get(joint, 'axis_angle', joint_key),
                                         f'{joint_key}.axis_angle'),
                initial_angle=fields.number(fields.get(joint, 'initial_angle', joint_key),
                                            f'{joint_key}.initial_angle'),
                lower_limit=limits[0], upper_limit=limits[1]))
        fingers.append(FingerDesign(
            position=fields.numbers(fields.get(finger, 'position', finger_key),
                                    f'{finger_key}.position', 2),
            segment_lengths=fields.numbers(fields.get(finger, 'segment_lengths', finger_key),
                                           f'{finger_key}.segment_lengths', len(joints)),
            joints=tuple(joints)))
    hand = HandDesign(fingers=tuple(fingers),
                      friction=fields.number(fields.get(document, 'friction', key),
                                             f'{key}.friction'))
    controller_key = f'{key}.controller'
    controller = fields.mapping(fields.get(document, 'controller', key), controller_key)
    rows = fields.get(controller, 'values', controller_key)
    if not isinstance(rows, list) or not rows:
        fields.fail(f'{controller_key}.values', 'a list of rows, one per knot')
    values = np.array([fields.numbers(row, f'{controller_key}.values[{index}]', hand.num_joints)
                       for index, row in enumerate(rows)], dtype=float)
    gains = {name: (np.array(fields.numbers(controller[name], f'{controller_key}.{name}',
                                            hand.num_joints)) if name in controller else None)
             for name in ('kp', 'kd')}
    return Design(hand=hand, controller=ControllerDesign(
        kind=str(fields.get(controller, 'kind', controller_key)), values=values,
        kp=gains['kp'], kd=gains['kd']))


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
                        task_document.get('structure'))
    except (TaskError, ValueError, TypeError) as error:
        raise UserError(f'{path}: task: cannot rebuild the task: {error}') from None
    design = design_from_document(fields.get(document, 'design', ''), fields)
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
    return Export(path=path, task=task, design=design,
                  urdf_path=path.parent / str(document.get('urdf', URDF_NAME)),
                  objective_names=names, objectives=values,
                  fitness=None if fitness is None else float(fitness), document=document)


def resimulate(exported, worlds=None):
    """Return the core Evaluation of an Export's design on its task (default: its worlds)."""
    try:
        return evaluate_design(exported.design, exported.task, worlds)
    except ValueError as error:
        raise UserError(f'{exported.path}: the design cannot be simulated: {error}') from None
