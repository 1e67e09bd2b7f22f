"""
`hand-codesign recover BAG`: close the bag of a recorder that was killed.

A recorder killed with SIGKILL (or a host that lost power) leaves its last MCAP file without
summary and footer and the bag folder without metadata.yaml: rosbags, `ros2 bag` and
Foxglove's reader refuse it, while `hand-codesign analyze` and `--resume` read it front to
back. This command rewrites every such file with the complete records it holds, closed and
indexed, and writes metadata.yaml covering all files of the folder (hand_codesign.bag.
recovery). Files already closed stay as they are; running it twice changes nothing.
"""

from hand_codesign.bag.files import BagError
from hand_codesign.bag.recovery import recover_bag
from hand_codesign.errors import UserError


def recover_command(arguments):
    """Recover the bag at arguments.bag; print what was done for each file."""
    try:
        report = recover_bag(arguments.bag)
    except BagError as error:
        raise UserError(str(error))
    for path, kept in report:
        if kept is None:
            print(f'{path}: already closed')
        else:
            print(f'{path}: recovered, {kept} messages kept, closed and indexed')
    return 0
