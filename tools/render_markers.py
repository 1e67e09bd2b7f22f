"""
Draw the markers of ROS 2 MCAP files with matplotlib, as a still of what Foxglove's 3D panel shows.

    python tools/render_markers.py OUT.png BAG.mcap:TOPIC[@SECONDS] [BAG.mcap:TOPIC[@SECONDS]]

Each argument after OUT.png is one panel: the MarkerArray of TOPIC at SECONDS after the file's
first message (default: the last one), decoded by mcap-ros2-support, drawn in the world frame.
Boxes, spheres, cylinders and arrows are drawn; other marker types are skipped. This is how
docs/look_at_a_run.png was made (README, "Look at a run").
"""

import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import numpy as np

ARROW, CUBE, SPHERE, CYLINDER = 0, 1, 2, 3
RESOLUTION = 16


def rotation(quaternion):
    """Return the 3x3 rotation matrix of a geometry_msgs Quaternion."""
    x, y, z, w = quaternion.x, quaternion.y, quaternion.z, quaternion.w
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def surfaces(marker):
    """Return the (x, y, z) grids of a box, sphere or cylinder marker's surface, or []."""
    u = np.linspace(0, 2 * np.pi, RESOLUTION)
    half = np.array([marker.scale.x, marker.scale.y, marker.scale.z]) / 2
    if marker.type == SPHERE:
        v = np.linspace(0, np.pi, RESOLUTION // 2)
        points = np.stack([np.outer(np.cos(u), np.sin(v)), np.outer(np.sin(u), np.sin(v)),
                           np.outer(np.ones_like(u), np.cos(v))])
    elif marker.type == CYLINDER:
        points = np.stack([np.outer(np.cos(u), [1, 1]), np.outer(np.sin(u), [1, 1]),
                           np.outer(np.ones_like(u), [-1, 1])])
    elif marker.type == CUBE:
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]], dtype=float)
        ring = np.stack([corners[:, 0], corners[:, 1]])
        sides = np.stack([np.stack([ring[0]] * 2, 1), np.stack([ring[1]] * 2, 1),
                          np.outer(np.ones(5), [-1, 1])])
        lids = [np.stack([np.array([[-1, 1], [-1, 1]]), np.array([[-1, -1], [1, 1]]),
                          np.full((2, 2), end)]) for end in (-1, 1)]
        return [place(marker, grid * half[:, None, None]) for grid in [sides] + lids]
    else:
        return []
    return [place(marker, points * half[:, None, None])]


def place(marker, points):
    """Return a (3, n, m) grid of points in the marker's frame moved to the world frame."""
    turned = np.einsum('ij,jkl->ikl', rotation(marker.pose.orientation), points)
    position = marker.pose.position
    return turned + np.array([position.x, position.y, position.z])[:, None, None]


def markers_at(path, topic, seconds):
    """Return the markers of the MarkerArray of topic at `seconds` (None: the last one)."""
    chosen, first = None, None
    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages():
            first = message.log_time if first is None else first
            if channel.topic != topic:
                continue
            if seconds is not None and (message.log_time - first) / 1e9 > seconds + 1e-9:
                break
            chosen = decoded
    if chosen is None:
        sys.exit(f'{path}: no MarkerArray on {topic}')
    return [marker for marker in chosen.markers if marker.action == 0]


def draw(axes, markers, title):
    """Draw markers into 3D axes with equal scales."""
    lows, highs = [], []
    for marker in markers:
        colour = (marker.color.r, marker.color.g, marker.color.b, marker.color.a)
        if marker.type == ARROW and len(marker.points) == 2:
            start, end = ([p.x, p.y, p.z] for p in marker.points)
            axes.plot(*zip(start, end), color=colour, linewidth=2)
            continue
        for grid in surfaces(marker):
            axes.plot_surface(*grid, color=colour, shade=True, linewidth=0)
            lows.append(grid.reshape(3, -1).min(axis=1))
            highs.append(grid.reshape(3, -1).max(axis=1))
    low, high = np.min(lows, axis=0), np.max(highs, axis=0)
    centre, reach = (low + high) / 2, (high - low).max() / 2
    for setter, middle in zip((axes.set_xlim, axes.set_ylim, axes.set_zlim), centre):
        setter(middle - reach, middle + reach)
    axes.set_box_aspect((1, 1, 1))
    axes.locator_params(nbins=4)
    axes.view_init(elev=20, azim=-60)
    axes.set_xlabel('x (m)')
    axes.set_ylabel('y (m)')
    axes.set_zlabel('z (m)')
    axes.set_title(title, fontsize=9)


def main(argv):
    """Render each BAG:TOPIC[@SECONDS] panel into one PNG."""
    if len(argv) < 2:
        sys.exit(__doc__)
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    figure = plt.figure(figsize=(4.2 * (len(argv) - 1), 4.2), dpi=90)
    for index, panel in enumerate(argv[1:]):
        path, _, rest = panel.partition('.mcap:')
        topic, _, at = rest.partition('@')
        seconds = float(at) if at else None
        axes = figure.add_subplot(1, len(argv) - 1, index + 1, projection='3d')
        when = f' at {seconds:g} s' if seconds is not None else ''
        draw(axes, markers_at(path + '.mcap', topic, seconds), f'{topic}{when}')
    figure.tight_layout()
    figure.savefig(argv[0])


if __name__ == '__main__':
    main(sys.argv[1:])
