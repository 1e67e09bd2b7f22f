"""
A still picture of a design on its task: the hand and the object at a rollout's start and end.

`analyze` puts one of the run's best design into report.md (`best_design.png`). One world is
re-simulated (analysis.replay.rollout_poses, the rollout `replay --world W` shows) and its
first and last frames are drawn side by side with matplotlib, from core.sim.geometry's shapes, the
very shapes of the `/best_design` markers and of `replay --mcap`: the palm box, each finger
segment as a cylinder between two spheres, each joint axis as a red line, the object, and a
translucent copy of it at each goal pose. Both panels share one view and one scale, so the
object's motion between them is what the design did.
"""

from hand_codesign.analysis.replay import rollout_poses
from hand_codesign.core.rotations import rotation_matrix
from hand_codesign.core.sim.geometry import GOAL_COLOUR
from hand_codesign.core.sim.geometry import goal_poses
from hand_codesign.core.sim.geometry import hand_shapes
from hand_codesign.core.sim.geometry import object_shapes
from hand_codesign.core.sim.worlds import object_state
import numpy as np

RESOLUTION = 16     # points around a sphere's or cylinder's surface
VIEW = (20.0, -60.0)    # matplotlib's elevation and azimuth, degrees
SIZE = (9.0, 4.5)   # inches, at 110 dots per inch


def _unit_surface(kind):
    """Return the (3, rows, columns) surface grids of a unit shape centred at its origin."""
    around = np.linspace(0, 2 * np.pi, RESOLUTION)
    if kind == 'sphere':
        along = np.linspace(0, np.pi, RESOLUTION // 2)
        return [np.stack([np.outer(np.cos(around), np.sin(along)),
                          np.outer(np.sin(around), np.sin(along)),
                          np.outer(np.ones_like(around), np.cos(along))])]
    if kind == 'cylinder':   # its axis is z, as a Marker's
        return [np.stack([np.outer(np.cos(around), [1, 1]), np.outer(np.sin(around), [1, 1]),
                          np.outer(np.ones_like(around), [-1, 1])])]
    ring = np.array([[-1, 1, 1, -1, -1], [-1, -1, 1, 1, -1]], dtype=float)
    sides = np.stack([np.stack([ring[0]] * 2, 1), np.stack([ring[1]] * 2, 1),
                      np.outer(np.ones(5), [-1, 1])])
    lids = [np.stack([np.array([[-1, 1], [-1, 1]]), np.array([[-1, -1], [1, 1]]),
                      np.full((2, 2), end)]) for end in (-1.0, 1.0)]
    return [sides] + lids


def shape_surfaces(shape):
    """Return the world-frame surface grids (3, rows, columns) of a box, sphere or cylinder."""
    half = np.asarray(shape.size, dtype=float)[:, None, None] / 2
    rotation = rotation_matrix(shape.orientation)
    position = np.asarray(shape.position, dtype=float)[:, None, None]
    return [np.einsum('ij,jkl->ikl', rotation, grid * half) + position
            for grid in _unit_surface(shape.kind)]


def draw_shapes(axes, shapes):
    """Draw Shapes into 3D axes; return every point drawn, (n, 3), to frame the view."""
    points = []
    for shape in shapes:
        if shape.kind == 'arrow':
            line = np.asarray(shape.points, dtype=float)
            axes.plot(*line.T, color=shape.colour[:3], linewidth=2)
            points.append(line)
            continue
        for grid in shape_surfaces(shape):
            axes.plot_surface(*grid, color=shape.colour[:3], alpha=shape.colour[3],
                              linewidth=0, shade=True)
            points.append(grid.reshape(3, -1).T)
    return np.concatenate(points)


def write_design_picture(path, task, design, world, pyplot):
    """
    Draw a RecordedDesign at the start and the end of its rollout in `world`; return path.

    task: the Task it was evaluated with (records.design_task); world: a core.sim.worlds
    WorldState; pyplot: matplotlib.pyplot with a non-interactive backend.
    """
    model, palm, frames = rollout_poses(task, design, world)
    state = object_state(task, world)
    shape = task.object_spec.shape
    ghosts = [ghost for _, position, orientation in goal_poses(task, state)
              for ghost in object_shapes(shape, state.size, (position, orientation), 'goals',
                                         GOAL_COLOUR)]
    figure = pyplot.figure(figsize=SIZE)
    panels, points = [], []
    for column, (label, (time, links, object_pose)) in enumerate(
            (('start', frames[0]), ('end', frames[-1]))):
        axes = figure.add_subplot(1, 2, column + 1, projection='3d')
        shapes = hand_shapes(model, palm, links) + object_shapes(shape, state.size,
                                                                 object_pose) + ghosts
        points.append(draw_shapes(axes, shapes))
        axes.set_title(f'{label}, t = {time:.2f} s')
        panels.append(axes)
    drawn = np.concatenate(points)
    centre = (drawn.min(axis=0) + drawn.max(axis=0)) / 2
    reach = float((drawn.max(axis=0) - drawn.min(axis=0)).max()) / 2
    for axes in panels:   # one cube for both: equal scales on every axis, the same view
        for set_limits, middle in zip((axes.set_xlim, axes.set_ylim, axes.set_zlim), centre):
            set_limits(middle - reach, middle + reach)
        axes.set_box_aspect((1, 1, 1))
        axes.view_init(*VIEW)
        axes.set_xlabel('x (m)')
        axes.set_ylabel('y (m)')
        axes.set_zlabel('z (m)')
    figure.suptitle(f'candidate {design.candidate_id} (generation {design.generation}), '
                    'goals translucent green')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)
    return path
