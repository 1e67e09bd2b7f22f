"""
`hand-codesign replay`: hand_codesign.analysis.replay, and with --mcap a rollout for Foxglove.

The --mcap file is written by hand_codesign.commands.replay_mcap, imported only then: a replay
to a GIF needs neither rclpy nor the messages.
"""

from hand_codesign.analysis import replay
from hand_codesign.errors import UserError


def replay_command(arguments):
    """Replay one design of a bag (see hand_codesign.analysis.replay); return the exit code."""
    write_mcap = None
    if arguments.mcap:
        if not arguments.mcap.endswith('.mcap'):
            raise UserError(f'--mcap {arguments.mcap}: expected a file name ending in .mcap')
        from hand_codesign.commands.replay_mcap import write_rollout_mcap as write_mcap
    return replay.replay_command(arguments, write_mcap=write_mcap)
