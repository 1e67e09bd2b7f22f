"""Evolutionary co-design of robot hands and their control (Meixner, Hazard, Pollard)."""
