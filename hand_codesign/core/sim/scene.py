"""
What the scenes of both engines share: gravity, the ground, and the bounds of a sane state.

Both simulators (core.sim.pybullet_sim, core.sim.mujoco_sim) build their ground and judge a
start collision or an exploded state by these values, so the engines differ in physics only.
"""

GRAVITY = -9.81  # m / s^2 along world z
GROUND_FRICTION = 1.0
COLLISION_TOLERANCE = 1e-6  # m of penetration that counts as a start collision
EXPLOSION_DISTANCE = 100.0  # m from the object's start: the simulation has exploded
EXPLOSION_JOINT_SPEED = 1e5  # rad / s
