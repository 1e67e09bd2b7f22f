"""
Old names that are still read, each with one line saying the name to use.

One name per quantity across the command line, the task file and the ROS parameters: the
candidates per generation are `population` (`--population`, `optimizer.population`, the
optimizer's parameter `population`), the randomized worlds per candidate `world_states`
(`--world-states`, `world_states`, the parameter `world_states`). The names they replaced,
`--popsize` and the task key `num_world_states`, still work and warn with OldName, a
FutureWarning (Python shows it by default, once per place). An entry point passes show_old_names
a function that writes one line: the CLI prints it, a node logs it.
"""

import warnings


class OldName(FutureWarning):
    """An old name of an option or key, still read as the new one."""


def warn_old_name(old, new, where=''):
    """Warn that `old` (in `where`, e.g. a task file) is read as `new`."""
    warnings.warn(f'{where}{old} is an old name, read as {new}: use {new}', OldName,
                  stacklevel=2)


def show_old_names(say):
    """Have every OldName warning from now on go to say(text) as one line; others as before."""
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, OldName):
            say(str(message))
        else:
            shown(message, category, filename, lineno, file, line)

    warnings.showwarning = show
