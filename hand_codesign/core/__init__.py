"""Pure-Python core of hand_codesign: tasks, hand model, simulation, objectives, optimizers."""

from hand_codesign.core.evaluate import evaluate, Evaluation
from hand_codesign.core.genome import decode, genome_spec, GenomeSpec, objective_names
from hand_codesign.core.sim import Simulator
from hand_codesign.core.task import load_task, parse_task, Task, TaskError
from hand_codesign.core.worlds import grid_world_states, world_states, WorldState

__all__ = [
    'decode', 'evaluate', 'Evaluation', 'genome_spec', 'GenomeSpec', 'grid_world_states',
    'load_task', 'objective_names', 'parse_task', 'Simulator', 'Task', 'TaskError',
    'world_states', 'WorldState',
]
