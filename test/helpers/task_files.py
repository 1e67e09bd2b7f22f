"""Task files for tests: the Task 5 preset with other optimizer settings, written to a folder."""

import pathlib

import yaml

TASK5 = pathlib.Path(__file__).resolve().parents[2] / 'config' / 'tasks' / 'task5.yaml'


def optimizer_document(algorithm, **keys):
    """Return task5.yaml as a dict with `algorithm` and every optimizer key not None set."""
    document = yaml.safe_load(TASK5.read_text())
    document['optimizer']['algorithm'] = algorithm
    document['optimizer'].update({key: value for key, value in keys.items()
                                  if value is not None})
    return document


def write_task(folder, document, name):
    """Write a task document to folder/name; return its path."""
    path = pathlib.Path(folder) / name
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path
