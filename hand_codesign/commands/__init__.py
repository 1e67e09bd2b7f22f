"""Commands that combine running and analysing; they sit above hand_codesign.ros and .analysis."""
