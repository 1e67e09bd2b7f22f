"""
The run room: what the optimizer node decides, as ROS-free code driven by events and a clock.

Modules: controller (the run), dispatch (who evaluates what, deadlines), audits (second
opinions), supervision (evaluator processes), evaluation_jobs (an evaluator's work), signing
(keys and signatures), summary (generation summaries), runs (the task a run used), preview
(what a run would do, for `check`). Imports everything of core but the rig room.
"""
