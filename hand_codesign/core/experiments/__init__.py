"""
The experiments room: the paper's experiments and what they measure of a design.

Modules: catalog (the experiments `reproduce` runs: configurations and budgets), measures
(a design on worlds it never trained on), robustness (a design over many world states, Fig.
3). Imports core's root, the task and sim rooms; never search, run or rig.
"""
