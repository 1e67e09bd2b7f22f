"""
The rig room: hardware in the loop without ROS, its simulated stand-in, and re-evaluation.

Modules: trials (a candidate's trials on a rig and their scoring), simulated (a simulated
rig), reevaluation (prediction and measurement of the same candidates). The top room of core:
it may import every other.
"""
