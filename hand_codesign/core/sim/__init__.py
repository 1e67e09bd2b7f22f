"""
The simulation room: the hand, the worlds, the policies, the objectives, and the two engines.

Modules: hand (a design as a PyBullet body), pybullet_sim (the PyBullet world and the one
rollout loop), mujoco_sim (the same world in MuJoCo), quiet_pybullet (loading PyBullet without
its banner), worlds (randomized world states), policies (torque and PD controllers),
objectives (eq. 2 to 6 from a pose trace), geometry (where a viewer draws what), physical (a
candidate's design in physical terms). Imports core's root and the task room, never search,
run, rig or experiments.
"""
