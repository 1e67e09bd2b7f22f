"""
The `optimizer` executable: the optimizer node, able to resume a run from its bag.

Resuming reads a bag (hand_codesign.analysis) and rebuilds the search (hand_codesign.core);
the node itself (hand_codesign.ros.optimizer_node) imports neither the analysis nor a bag
reader, so this command, above both, hands it the function that does.
"""

import sys

from hand_codesign.ros import optimizer_node


def load_resume(bag, iterations=0):
    """
    Return the core.search.resume.ResumePoint of the run recorded in bag.

    iterations > 0: continue it to that many generations (more than its own).
    """
    # imported here: a fresh run never reads a bag and starts without the bag readers
    from hand_codesign.analysis.resume import resume_point
    return resume_point(bag, iterations)


def main(args=None):
    """Run the optimizer node with `load_resume` for its resume_bag parameter."""
    return optimizer_node.main(args, load_resume=load_resume)


if __name__ == '__main__':
    sys.exit(main())
