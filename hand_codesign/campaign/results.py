"""A campaign folder's results: its tables (.csv, .md) and figures, from its measures."""

import pathlib

from hand_codesign.campaign.experiment import seeds_text
from hand_codesign.campaign.figures import convergence_panels
from hand_codesign.campaign.figures import plot_convergence
from hand_codesign.campaign.figures import plot_errors
from hand_codesign.campaign.folders import load_measures
from hand_codesign.campaign.tables import configuration_rows
from hand_codesign.campaign.tables import markdown_table
from hand_codesign.campaign.tables import structure_rows
from hand_codesign.campaign.tables import write_table


def write_results(out, experiment, budget, seeds, figure_format='png'):
    """
    Write the tables (.csv, .md) and figures of a campaign folder; return their paths.

    figure_format: 'png', 'svg' or 'pdf', the figures' format (report.md shows each).
    """
    out = pathlib.Path(out)
    measured = load_measures(out, experiment, seeds)
    rows = configuration_rows(experiment, budget, measured)
    name = experiment.name
    paths = [out / f'{name}.csv', out / f'{name}.md', out / f'{name}.{figure_format}']
    write_table(out, name, rows, experiment.also)
    lines = [f'# {name}', '', experiment.summary + '.', '',
             f'Budget {budget.describe()}; {seeds_text(seeds)}; a row per configuration, '
             'the unseen worlds of its seeds pooled.', '',
             markdown_table(rows, experiment.tolerance, also=experiment.also)]
    labels = [f'{row["policy"]} {row["algorithm"]} {row["world_states"]}w' for row in rows]
    if len(set(labels)) < len(labels):  # levers that differ by a task option, not algorithm
        labels = [row['configuration'] for row in rows]
    groups = [(label, measured[row['configuration']]) for label, row in zip(labels, rows)]
    if groups:
        plot_errors(paths[2], groups, experiment.tolerance, f'{name}, {budget.name} budget')
        lines += [f'![{paths[2].name}]({paths[2].name})', '']
    else:
        paths.pop()
    if experiment.per_structure:
        by_structure = load_measures(out, experiment, seeds, '.structures')
        rows = structure_rows(experiment, budget, by_structure)
        write_table(out, f'{name}-structures', rows, experiment.also)
        figure = out / f'{name}-structures.{figure_format}'
        plot_errors(figure, [(row['structure'], [values for record in
                                                 by_structure[row['configuration'].split()[0]]
                                                 for text, values in record.items()
                                                 if text == row['structure']])
                             for row in rows],
                    experiment.tolerance, f"{name}: each structure's best (Fig. 3)",
                    kinds=('position', 'orientation'))
        lines += ["## Each structure's best design (Fig. 3)", '',
                  markdown_table(rows, experiment.tolerance, 'structure', experiment.also),
                  f'![{figure.name}]({figure.name})', '']
        paths += [out / f'{name}-structures.csv', figure]
    panels = convergence_panels(out, experiment, seeds) if experiment.convergence else []
    if panels:
        figure = out / f'{name}-convergence.{figure_format}'
        plot_convergence(figure, panels, f'{name}, {budget.name} budget')
        lines += ['## Convergence', '', f'![{figure.name}]({figure.name})', '']
        paths.append(figure)
    paths[1].write_text('\n'.join(lines), encoding='utf-8')
    return paths
