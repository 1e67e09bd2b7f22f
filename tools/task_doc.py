"""
Write docs/TASK.md's table of task-file keys from the schema (hand_codesign.core.task.schema).

Usage: python tools/task_doc.py   (rewrites the table between the file's markers; the prose
around it is edited by hand). test_task_schema fails while the file is not what this writes.
"""

import pathlib

from hand_codesign.core.task.document import with_keys

PATH = pathlib.Path(__file__).resolve().parents[1] / 'docs' / 'TASK.md'


def main():
    text = PATH.read_text(encoding='utf-8')
    PATH.write_text(with_keys(text), encoding='utf-8')
    print(f'wrote the keys of {PATH}')


if __name__ == '__main__':
    main()
