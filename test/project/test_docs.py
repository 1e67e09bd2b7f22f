"""
The user docs: short front pages, no issue numbers, links that resolve, options that exist.

README.md stays at most 150 lines and docs/RESULTS.md at most 180; neither they nor any
Markdown page under docs/ cites an issue by number (a reader cannot open it); every relative
link of README.md, docs/*.md and the experiment pages docs/results/**/README.md names a file
that exists; every `--option` the README shows for `hand-codesign VERB` is in that verb's
`--help`.
"""

import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
README = ROOT / 'README.md'
RESULTS = ROOT / 'docs' / 'RESULTS.md'
COMMAND = pathlib.Path(sys.prefix) / 'bin' / 'hand-codesign'
ISSUE = re.compile(r'\bissues? \d+|#\d+', re.IGNORECASE)
LINK = re.compile(r'\[[^\]]*\]\(([^)\s]+)\)')
VERBS = ('check', 'run', 'analyze', 'replay', 'robustness', 'export', 'recover', 'evaluate',
         'reproduce', 'offsets', 'transfer')
# an inline `VERB ...` or `hand-codesign VERB ...` in the README's prose
INLINE = re.compile(r'`(?:hand-codesign )?(' + '|'.join(VERBS) + r') ([^`]*)`')


def linked_pages():
    """Return README.md, docs/*.md and every docs/results/**/README.md."""
    return [README, *sorted((ROOT / 'docs').glob('*.md')),
            *sorted((ROOT / 'docs' / 'results').glob('**/README.md'))]


def readme_commands():
    """
    Return {verb: options} the README shows.

    From its code blocks' `hand-codesign VERB` lines and its prose's inline `VERB ...` or
    `hand-codesign VERB ...`. A line indented under a `hand-codesign` line continues it; `#`
    starts a comment.
    """
    commands = {}
    verb = None
    parts = README.read_text(encoding='utf-8').split('```')
    for verb, rest in INLINE.findall(''.join(parts[0::2])):
        commands.setdefault(verb, set()).update(re.findall(r'(?<![\w-])--[a-z][\w-]*', rest))
    verb = None
    blocks = parts[1::2]
    for line in '\n'.join(blocks).splitlines():
        code = line.split('#')[0]
        if line.startswith('hand-codesign '):
            words = code.split()
            verb = words[1] if not words[1].startswith('-') else ''
        elif not line.startswith(' '):
            verb = None
        if verb is not None:
            commands.setdefault(verb, set()).update(re.findall(r'(?<![\w-])--[a-z][\w-]*', code))
    return commands


def test_the_front_pages_are_short():
    assert len(README.read_text(encoding='utf-8').splitlines()) <= 150
    assert len(RESULTS.read_text(encoding='utf-8').splitlines()) <= 180


def test_no_page_cites_an_issue_by_number():
    pages = [README, *sorted((ROOT / 'docs').glob('**/*.md')), ROOT / 'bench' / 'README.md']
    found = [f'{page.relative_to(ROOT)}:{number}: {line.strip()}'
             for page in pages
             for number, line in enumerate(page.read_text(encoding='utf-8').splitlines(), 1)
             if ISSUE.search(line)]
    assert not found, '\n'.join(found)


def test_every_relative_link_resolves():
    pages = linked_pages()
    assert ROOT / 'docs' / 'results' / 'README.md' in pages
    missing = []
    for page in pages:
        for target in LINK.findall(page.read_text(encoding='utf-8')):
            path = target.split('#')[0]
            if not path or re.match(r'[a-z]+:', path):
                continue  # an anchor on the same page, or a URL
            if not (page.parent / path).exists():
                missing.append(f'{page.relative_to(ROOT)} -> {target}')
    assert not missing, '\n'.join(missing)


def test_every_experiment_page_is_in_the_index():
    index = (ROOT / 'docs' / 'results' / 'README.md').read_text(encoding='utf-8')
    results = RESULTS.read_text(encoding='utf-8')
    for name in ('task5-joint-limits', 'task6-rotation', 'task4-hierarchy', 'task4-structures',
                 'task1-seeded', 'task2-seeded', 'task3-levers', 'fixed-hand', 'levers-task5',
                 'levers-task6', 'engines'):
        assert f'({name}/README.md)' in index, name
        assert f'(results/{name}/README.md)' in results, name


def test_the_readme_shows_the_animation_and_the_two_commands():
    text = README.read_text(encoding='utf-8')
    assert '](docs/best_rollout.gif)' in text and 'make animation' in text
    assert 'make demo' in text and 'make test' in text
    assert '| task (paper) | ours |' in text  # the headline table


@pytest.mark.parametrize('verb', sorted(readme_commands()))
@pytest.mark.system
def test_every_option_the_readme_shows_exists(verb):
    shown = readme_commands()[verb]
    arguments = [verb, '--help'] if verb else ['--help']
    process = subprocess.run([str(COMMAND), *arguments], cwd=ROOT, capture_output=True,
                             text=True, timeout=120)
    assert process.returncode == 0, process.stderr
    offered = set(re.findall(r'--[a-z][\w-]*', process.stdout))
    assert shown <= offered, f'hand-codesign {verb}: {sorted(shown - offered)} not in --help'


def test_the_readme_shows_every_verb_it_names():
    assert {*VERBS, ''} <= set(readme_commands())
