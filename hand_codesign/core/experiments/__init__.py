"""
The experiments room: what the paper's experiments measure of a design.

Modules: measures (a design on worlds it never trained on, and the tolerances it is judged
by), robustness (a design over many world states, Fig. 3), motion (one world's rollout of a
design frame by frame, and its URDF: what a robot model in a viewer shows). The experiments
themselves, their configurations and budgets, are the campaign room's
(hand_codesign.campaign). Imports core's root, the task and sim rooms; never search, run or
rig.
"""
