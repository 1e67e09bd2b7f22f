"""Pure-Python core of hand_codesign: tasks, hand model, simulation, objectives, optimizers."""
