"""
A task file seeded from an exported design: its `seed_design` block replaced, the rest kept.

`hand-codesign export BAG --out DIR` writes DIR/controller.yaml, whose `design` is in the
format of a task's `seed_design`. This writes a copy of TASK.yaml (its text and comments kept)
whose top-level `seed_design` block is that design, headed by a comment naming its source, so a
seeded search (Tasks 1 and 2: deltas around the seed) starts from it. Floats keep their exact
shortest repr: contact-rich motions are sensitive, and a design rounded to four decimals can
end a nominal rollout far from where the exported one does.

Usage: python tools/seed_task.py TASK.yaml EXPORT_DIR OUT.yaml   (from the repository's root)
"""

import argparse
import pathlib
import sys
import textwrap

from hand_codesign.analysis.export import load_export
from hand_codesign.core.task import load_task
from hand_codesign.core.task import TaskError
from hand_codesign.errors import UserError
import yaml


def without_block(text, key):
    """
    Return the lines of a YAML text without its top-level `key:` block and its comments.

    The comment lines right above the key are taken as its own: they describe it.
    """
    kept, skipping = [], False
    for line in text.splitlines():
        if line[:1] not in ('', ' ', '#'):  # a top-level key
            skipping = line.startswith(f'{key}:')
            while skipping and kept and kept[-1].startswith('#'):
                kept.pop()
        if not skipping:
            kept.append(line)
    while kept and not kept[-1].strip():
        kept.pop()
    return kept


def seeded_text(task_text, design, source):
    """Return task_text with its seed_design replaced by `design` (a plain mapping)."""
    block = yaml.safe_dump({'seed_design': design}, sort_keys=False, default_flow_style=None)
    heading = textwrap.wrap(f'The seed design: {source}.', 93, break_on_hyphens=False)
    return '\n'.join(without_block(task_text, 'seed_design') + ['']
                     + [f'# {line}' for line in heading] + [block.rstrip()]) + '\n'


def main():
    """Write OUT.yaml: TASK.yaml seeded from the design of an export folder."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('task', type=pathlib.Path, help='the task file to copy')
    parser.add_argument('export', type=pathlib.Path, help='a folder of hand-codesign export')
    parser.add_argument('out', type=pathlib.Path, help='the task file to write')
    arguments = parser.parse_args()
    try:
        write_seeded(arguments.task, arguments.export, arguments.out)
    except (UserError, TaskError, OSError) as error:
        print(f'seed_task: {error}', file=sys.stderr)
        return 2
    return 0


def write_seeded(task, export, out):
    """Write `out`: the task file `task` seeded from the design of the export folder `export`."""
    document = load_export(export).document  # checked as an export reads back
    origin = document['source']
    source = (f"candidate {origin['candidate_id']} of run {origin['run_id']} "
              f"(seed {document['task']['seed']}), exported by hand-codesign export")
    design = document['design']
    text = seeded_text(task.read_text(), design, source)
    draft = out.with_name(out.name + '.draft')
    try:
        draft.write_text(text)
        load_task(draft)  # the written task must read back before it replaces `out`
        draft.replace(out)
    finally:
        draft.unlink(missing_ok=True)
    print(f'wrote {out}')


if __name__ == '__main__':
    sys.exit(main())
