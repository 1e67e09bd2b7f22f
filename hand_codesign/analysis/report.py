"""
`hand-codesign analyze BAG [--out DIR]`: a report folder of a run, from its bag alone.

Writes into DIR (default: `<bag>_report` next to the bag):

- `evaluations.csv`: one row per Evaluation message, in recorded order: generation, candidate
  id, evaluator, status (ok, rejected, or duplicate: a later answer the optimizer ignored),
  every objective by name, fitness, collision, unstable worlds, simulated and wall time, the
  rejection reason, and the candidate's normalized genome by gene name. Numbers are written
  with Python's shortest exact repr, so they read back bit for bit; an empty cell is a value
  the message does not have (objectives of a rejection, genes of another structure).
- `generations.csv` and `convergence.png`: best and median of each objective per generation
  (from the GenerationSummary messages, or from the evaluations when the bag has none) and the
  best fitness so far.
- `pareto.png` and `pareto_front.csv` for MO-CMA-ES runs: the Pareto front of every
  generation, coloured by generation, and the final front.
- `archive.png` and `archive.csv` for quality-diversity runs (cma-mae, cma-me): a heat map of
  the archive over its two descriptors, each cell coloured by its elite's weighted sum, and
  every elite (candidate id, generation, cell, descriptor values, weighted sum), best first.
  The archive is rebuilt by replaying the search from the bag's evaluations.
- `best_design.png`: the best design re-simulated in the run's world 0, drawn at the start
  and at the end of the rollout (analysis.design_picture).
- `search_state.png` and `search_state.csv`: the search's own state per generation
  (analysis.search_state): CMA-ES's step size and axis ratio, MO-CMA-ES's hypervolume, the
  archive's coverage and QD score for CMA-MAE and CMA-ME.
- With `--format svg` or `pdf` every figure is written in that format instead of PNG.
- `report.md`: task, seed, budget, wall time, evaluations per second, the figures, and the
  best design, its picture and its parameters in physical units; for a run with restarts (ipop-cma,
  bipop-cma) the generation, population and cause of each restart (the search replayed); for
  a quality-diversity run the archive's best designs.

It prints a summary table to the terminal.
"""

import pathlib

from hand_codesign.analysis import records
from hand_codesign.analysis.figures import load_pyplot, plot_archive, plot_convergence, plot_pareto
from hand_codesign.analysis.generations import (generations_from_evaluations,
                                                generations_from_summaries, pareto_fronts,
                                                restart_facts, STAGE_WORLDS)
from hand_codesign.analysis.rig_report import rig_comparison
from hand_codesign.analysis.search_state import plot_search_state, search_state
from hand_codesign.analysis.tables import (aligned_table, float_texts, int_texts, markdown_cell,
                                           number_text, write_csv, write_evaluations_csv)
from hand_codesign.analysis.trust import trust_facts
from hand_codesign.core.sim.worlds import world_states
from hand_codesign.core.task import TaskError
from hand_codesign.core.task.genome import genome_spec
from hand_codesign.errors import UserError
from hand_codesign.outputs import staged
from hand_codesign.version import version_text
import numpy as np

MAX_TABLE_ROWS = 12
DESIGN_PICTURE = 'best_design'   # and the figures' suffix
ELITES_LISTED = 10  # the archive's best designs in the terminal and in report.md


def analyze_command(arguments):
    """Write the report folder of a bag; return the exit code."""
    if getattr(arguments, 'engine', None) and not getattr(arguments, 'unseen', 0):
        raise UserError('--engine: measures the final design on unseen worlds; give --unseen N '
                        'too')
    record = records.open_run(arguments.bag)
    out = pathlib.Path(arguments.out) if arguments.out else default_report_dir(record.path)
    report = Report(record)
    with staged(out) as folder:
        files = report.write(folder, getattr(arguments, 'format', None) or 'png')
        print(report.summary_text())
        if getattr(arguments, 'unseen', 0):
            files += write_unseen(record.path, folder, arguments.unseen,
                                  getattr(arguments, 'engine', None))
    print(f'report: {out} ({", ".join(sorted(path.name for path in files))})')
    return 0


def write_unseen(bag, out, count, engine=None):
    """Measure the best design on `count` unseen worlds (in `engine`: default the run's)."""
    import json
    # imported here: measuring simulates (PyBullet), the rest of the report does not
    from hand_codesign.analysis.unseen import unseen_report
    if count < 1:
        raise UserError(f'--unseen: expected a positive number of worlds, got {count}')
    lines, values = unseen_report(bag, count, processes=2, engine=engine)
    paths = [out / 'unseen.md', out / 'unseen.json']
    paths[0].write_text('\n'.join(lines) + '\n', encoding='utf-8')
    paths[1].write_text(json.dumps(values, indent=2) + '\n', encoding='utf-8')
    print('\n'.join(lines))
    return paths


def default_report_dir(bag_path):
    """Return `<bag>_report` next to the bag (a folder, or an .mcap file without suffix)."""
    return records.beside_bag(bag_path, '_report')


def evaluation_counts(status):
    """Return the line counting a run's evaluations by status (records.evaluation_rows)."""
    count = {name: int((status == name).sum()) for name in
             ('ok', 'round', 'rejected', 'duplicate', 'untold')}
    return (f'{count["ok"] + count["round"]} ok'
            + (f' ({count["round"]} of them racing rounds)' if count['round'] else '')
            + f', {count["rejected"]} rejected, {count["duplicate"]} duplicate'
            + (f', {count["untold"]} untold (answers the summaries contradict)'
               if count['untold'] else ''))


class Report:
    """The report of one RunRecord: tables, figures and text."""

    def __init__(self, record):
        self.record = record
        self.info = record.run_info
        self.rows = records.evaluation_rows(record)
        self.names = self.rows.objective_names
        self.task = None
        self.task_problem = ''
        if self.info is not None:
            try:
                self.task = records.run_task_of(record)
            except UserError as error:
                self.task_problem = str(error)
        weights = self.task.objective_weights if self.task is not None else None
        if len(record.generation_summaries):
            self.generations = generations_from_summaries(record, len(self.names))
        else:
            self.generations = generations_from_evaluations(self.rows, weights)
        self.fronts = (pareto_fronts(record, len(self.names), self.generations.rows)
                       if self.names else [])
        self.best = self._best_design()
        self.restarts = records.restarts_of(record)  # of ipop-cma, bipop-cma; else []
        self.archive = records.archive_of(record)  # of cma-mae, cma-me; else None
        self.search = search_state(record, self.fronts)   # sigma, hypervolume, QD score
        self.elites = self.archive.elites() if self.archive is not None else []
        self.rig = rig_comparison(record)   # prediction against measurement, if any
        self.picture = None   # best_design.png, once written

    # ---------------------------------------------------------------- facts

    def _best_design(self):
        if not self.rows.ok.any() and not len(self.record.generation_summaries):
            return None
        try:
            design = records.recorded_design(self.record,
                                             records.best_candidate_id(self.record))
        except UserError as error:
            self.task_problem = self.task_problem or str(error)
            return None
        if design.objectives is None:
            summary = records.last_summary(self.record)
            if summary is not None and int(summary['best_candidate_id']) == design.candidate_id:
                design.objectives = np.asarray(summary['best_objectives'], dtype=float)
                design.fitness = float(summary['best_fitness'])
        return design

    @property
    def wall_time(self):
        """Return the run's wall time in seconds (the optimizer's, else the bag's span)."""
        summary = records.last_summary(self.record)
        if summary is not None and summary['wall_time'] > 0:
            return float(summary['wall_time'])
        return (self.record.end_time - self.record.start_time) / 1e9

    def facts(self):
        """Return [(label, text)] describing the run."""
        info, rows, record = self.info, self.rows, self.record
        used = np.isin(rows.status, ('ok', 'round'))  # a racing round's answers are used too
        ok = int(used.sum())
        facts = [('bag', record.path), ('run', record.run_id or '(unknown)')]
        if info is not None:
            facts += [('task', info.task_name), ('seed', str(info.seed)),
                      ('algorithm', info.algorithm),
                      ('budget', f'{info.iterations} generations x {info.population} '
                                 f'candidates x {info.world_states} world states = '
                                 f'{info.iterations * info.population} evaluations, '
                                 f'{info.iterations * info.population * info.world_states} '
                                 'rollouts')]
            if self.task is not None and self.task.hierarchy is not None:
                facts.append(('hierarchy', f'structures from {list(self.task.hierarchy.start)}'
                                           ' (budget per structure)'))
            elif self.task is not None:
                facts.append(('structure', str(list(self.task.structure))))
            if self.task is not None and self.task.worlds.resample != 'none':
                checks = min(self.task.worlds.final_check, info.iterations)
                facts.append(('worlds', f'a fresh draw per generation, then a final check of '
                                        f'{checks} designs on the fixed worlds'))
            if self.task is not None and self.task.worlds.aggregate == 'worst':
                facts.append(('scoring', f'each objective over its worst '
                                         f'{self.task.worlds.fraction:g} of the worlds (CVaR)'))
            if info.resumed_from:
                facts.append(('resumed from', info.resumed_from))
            facts += restart_facts(self.restarts)
            facts += racing_facts(record)
            facts += self.archive_facts()
        else:
            facts.append(('task', '(unknown: the bag holds no RunInfo)'))
        wall = self.wall_time
        facts += [
            ('evaluations', evaluation_counts(rows.status)),
            ('generations', f'{len(self.generations)} (from {self.generations.source})'),
            ('wall time', f'{wall:.1f} s'),
            ('evaluations per second', f'{ok / wall:.2f}' if wall > 0 else 'n/a'),
        ]
        simulated = float(np.sum(rows.simulated_time[used]))
        if wall > 0 and simulated > 0:
            facts.append(('simulated time', f'{simulated:.1f} s ({simulated / wall:.1f} '
                                            'simulated s per wall s)'))
        evaluators = sorted(set(rows.evaluator_id[used].tolist()))
        facts.append(('evaluators', str(len(evaluators)) + (
            f': {", ".join(evaluators[:8])}' + (' ...' if len(evaluators) > 8 else '')
            if evaluators else '')))
        summary = records.last_summary(record)
        if summary is not None:
            facts.append(('stopped', 'yes: ' + (summary['stop_reason'] or 'final')
                          if summary['final'] else 'no final summary (run interrupted?)'))
        facts += trust_facts(record)
        if record.truncated:
            facts.append(('bag state', 'truncated: read up to the cut'))
        return facts

    def archive_facts(self):
        """Return [('archive', text)] of a quality-diversity run, else []."""
        archive = self.archive
        if archive is None:
            return []
        cells = archive.cells[0] * archive.cells[1]
        axes = ' x '.join(f'{name} [{low:.4g}, {high:.4g}]' for name, (low, high) in
                          zip(archive.describe.names, archive.ranges))
        return [('archive', f'{len(self.elites)} of {cells} cells filled, over {axes} '
                            f'({len(archive.batch_sizes)} emitters, '
                            f'{sum(archive.emitter_restarts)} restarts)')]

    def elite_rows(self, count=None):
        """Return the listed elites as rows of text: id, generation, descriptors, fitness."""
        recommended = self.archive.result.candidate_id if self.archive.result else None
        rows = []
        for elite in self.elites[:count]:
            rows.append([str(elite.candidate_id), str(elite.generation)]
                        + [f'{value:.4g}' for value in elite.descriptors]
                        + [f'{elite.fitness:.4g}',
                           'recommended' if elite.candidate_id == recommended else ''])
        return rows

    def elite_header(self):
        names = self.archive.describe.names
        units = self.archive.describe.units
        return (['candidate', 'generation']
                + [f'{name} ({unit})' if unit else name for name, unit in zip(names, units)]
                + ['fitness', ''])

    def write_archive_csv(self, path):
        archive = self.archive
        names = list(archive.describe.names)
        header = (['candidate_id', 'generation'] + [f'cell_{name}' for name in names] + names
                  + ['fitness'])
        elites = self.elites
        columns = [[str(e.candidate_id) for e in elites], [str(e.generation) for e in elites]]
        columns += [[str(e.cell[i]) for e in elites] for i in range(2)]
        columns += [float_texts(np.array([e.descriptors[i] for e in elites]))
                    for i in range(2)]
        columns.append(float_texts(np.array([e.fitness for e in elites])))
        write_csv(path, header, columns)

    def archive_markdown(self):
        if self.archive is None:
            return []
        figure = f'archive.{getattr(self, "suffix", "png")}'
        lines = ['', '## Archive', '', f'![{figure}]({figure})', '',
                 f'Its {min(ELITES_LISTED, len(self.elites))} best designs of '
                 f'{len(self.elites)} (all in `archive.csv`); the recommended one is the '
                 "run's result:", '']
        header = self.elite_header()
        lines += ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
        lines += ['| ' + ' | '.join(row) + ' |' for row in self.elite_rows(ELITES_LISTED)]
        return lines

    def archive_text(self):
        if self.archive is None:
            return ''
        rows = self.elite_rows(ELITES_LISTED)
        return (f'archive: the {len(rows)} best of {len(self.elites)} elites\n'
                + aligned_table([self.elite_header()] + rows))

    def best_parameters(self):
        """Return [(gene, physical value, unit, lower, upper, normalized)] of the best design."""
        design = self.best
        if design is None or self.info is None:
            return []
        try:
            task = records.design_task(self.record, design)
            spec = genome_spec(task)
            values = spec.design_values(design.x)
        except (UserError, ValueError) as error:
            self.task_problem = self.task_problem or str(error)
            return []
        return [(name, value, records.gene_unit(name), lower, upper, x)
                for name, value, lower, upper, x in zip(spec.names, values.values(),
                                                        spec.lower, spec.upper, design.x)]

    # ---------------------------------------------------------------- files

    def write(self, out, suffix='png'):
        """Write every file of the report into folder out (figures as suffix); return them."""
        self.suffix = suffix
        out = pathlib.Path(out)
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise UserError(f'--out {out}: cannot create the folder: {error}') from None
        files = [out / 'evaluations.csv', out / 'generations.csv']
        write_evaluations_csv(files[0], self.rows)
        self.write_generations_csv(files[1])
        figures = []
        if len(self.generations) and self.names:
            figures.append(plot_convergence(out / f'convergence.{suffix}', self.generations,
                                            self.names, self.record.run_id, self.restarts))
        if self.fronts:
            figures.append(plot_pareto(out / f'pareto.{suffix}', self.fronts, self.names))
            files.append(out / 'pareto_front.csv')
            self.write_front_csv(files[-1])
        if self.search is not None:
            figures.append(plot_search_state(out / f'search_state.{suffix}', self.search,
                                             self.record.run_id, self.restarts))
            files.append(out / 'search_state.csv')
            self.search.write_csv(files[-1])
        files += figures
        if self.archive is not None and self.elites:
            files.append(plot_archive(out / f'archive.{suffix}', self.archive,
                                      self.record.run_id))
            files.append(out / 'archive.csv')
            self.write_archive_csv(files[-1])
        if self.rig is not None:
            files.append(out / 'rig_gap.csv')
            self.rig.write_csv(files[-1])
            files.append(self.rig.plot(out / f'rig_gap.{suffix}', load_pyplot()))
        files += self.write_picture(out / f'{DESIGN_PICTURE}.{suffix}')
        files.append(out / 'report.md')
        files[-1].write_text(self.markdown([figure.name for figure in figures]),
                             encoding='utf-8')
        return files

    def write_picture(self, path):
        """Draw the best design at the start and end of world 0; return [path], or []."""
        self.picture = None
        if self.best is None or self.task is None:
            return []
        try:
            task = records.design_task(self.record, self.best)
        except (UserError, TaskError) as error:   # a bag whose design cannot be rebuilt
            self.task_problem = self.task_problem or str(error)
            return []
        if len(self.best.x) != genome_spec(task).size:   # a bag of another task's genomes
            return []
        # imported here: the picture simulates (PyBullet), the rest of the report does not
        from hand_codesign.analysis.design_picture import write_design_picture
        self.picture = write_design_picture(path, task, self.best, world_states(task)[0],
                                            load_pyplot())
        return [self.picture]

    def write_generations_csv(self, path):
        generations = self.generations
        header = (['structure', 'generation']
                  + [f'best_{name}' for name in self.names]
                  + [f'median_{name}' for name in self.names]
                  + ['best_fitness_so_far', 'evaluations', 'wall_time']
                  + (['horizon'] if generations.horizons.any() else [])
                  + (['stage'] if generations.stages.any() else []))
        columns = [['x'.join(str(j) for j in structure) for structure in generations.structures],
                   int_texts(generations.generations)]
        columns += [float_texts(generations.best[:, i]) for i in range(len(self.names))]
        columns += [float_texts(generations.median[:, i]) for i in range(len(self.names))]
        columns += [float_texts(generations.best_fitness),
                    [number_text(value) if value != value else str(int(value))
                     for value in generations.evaluations.tolist()],
                    float_texts(generations.wall_time)]
        if generations.horizons.any():
            columns.append(float_texts(generations.horizons))
        if generations.stages.any():
            columns.append(int_texts(generations.stages))
        write_csv(path, header, columns)

    def write_front_csv(self, path):
        index, generation, front = self.fronts[-1]
        columns = [[str(generation)] * len(front)]
        columns += [float_texts(front[:, i]) for i in range(front.shape[1])]
        write_csv(path, ['generation'] + list(self.names), columns)

    # ---------------------------------------------------------------- text

    def markdown(self, figure_names):
        """Return report.md."""
        lines = [f'# Run {self.record.run_id or "(unknown)"}', '', '| | |', '|---|---|']
        lines += [f'| {label} | {markdown_cell(text)} |' for label, text in self.facts()]
        lines.append(f'| report by | hand-codesign {version_text()} |')
        if self.record.warnings:
            lines += ['', '## Warnings from reading the bag', '']
            lines += [f'- {markdown_cell(warning)}' for warning in self.record.warnings]
        lines += ['', '## Convergence', '']
        for name in figure_names:
            lines += [f'![{name}]({name})', '']
        lines += self.best_markdown()
        lines += self.archive_markdown()
        if self.rig is not None:
            lines += self.rig.markdown(f'rig_gap.{getattr(self, "suffix", "png")}')
        lines += ['', '## Files', '',
                  '- `evaluations.csv`: every evaluation (normalized genome by gene name)',
                  '- `generations.csv`: best and median of each objective per generation']
        if self.fronts:
            lines.append('- `pareto_front.csv`: the final Pareto front')
        if self.elites:
            lines.append('- `archive.csv`: every elite of the archive, best first')
        if self.search is not None:
            lines.append("- `search_state.csv`: the search's state per generation"
                         + (f' ({self.search.note})' if self.search.note else ''))
        if self.task is not None:
            lines += ['', '## Task file as run', '', '```yaml', self.info.task_yaml.rstrip(),
                      '```']
        return '\n'.join(lines) + '\n'

    def best_markdown(self):
        design = self.best
        lines = ['## Best design', '']
        if design is None:
            return lines + ['No design was evaluated successfully.']
        stage = (f' of stage {design.stage} ({STAGE_WORLDS[design.stage]})'
                 if design.stage else '')
        if design.world_draw:
            stage += f' on resampled worlds (draw {design.world_draw})'
        elif self.task is not None and self.task.worlds.resample != 'none':
            stage += ', its final check on the fixed worlds (the run resampled its worlds)'
        lines.append(f'Candidate {design.candidate_id} of generation {design.generation}{stage}, '
                     f'structure {list(design.structure)}, evaluated by '
                     f'{design.evaluator_id or "(no evaluation in the bag)"}'
                     + (f' up to the horizon {design.horizon:g} s (its objectives are those of '
                        'that sub-problem).' if design.horizon else '.'))
        if self.picture is not None:
            lines += ['', f'![The best design at the start and the end of world 0]'
                          f'({self.picture.name})', '',
                      'Re-simulated in world 0 of the run (`hand-codesign replay BAG --world 0` '
                      'animates it): start and end of the rollout.']
        if design.objectives is not None:
            lines += ['', '| objective | value |', '|---|---|']
            lines += [f'| {name} | {value:.6g} |'
                      for name, value in zip(self.names, design.objectives)]
            lines.append(f'| fitness (weighted sum) | {design.fitness:.6g} |')
        parameters = self.best_parameters()
        if parameters:
            lines += ['', '| parameter | value | unit | lower | upper | normalized |',
                      '|---|---|---|---|---|---|']
            lines += [f'| {name} | {value:.6g} | {unit} | {lower:.6g} | {upper:.6g} | '
                      f'{x:.4f} |' for name, value, unit, lower, upper, x in parameters]
            lines += ['', 'Joint limit pairs are sorted and initial angles clipped into them '
                          'when the design is built.']
        elif self.task_problem:
            lines += ['', f'Parameters in physical units unavailable: {self.task_problem}']
        return lines

    def summary_text(self):
        """Return the terminal summary: facts, a table of generations, the best design."""
        width = max(len(label) for label, _ in self.facts())
        lines = [f'{label:<{width}}  {text}' for label, text in self.facts()]
        lines += ['', self.generation_table()]
        design = self.best
        if design is not None:
            objectives = ('' if design.objectives is None else ', '.join(
                f'{name} {value:.4g}' for name, value in zip(self.names, design.objectives)))
            fitness = '' if design.fitness is None else f'fitness {design.fitness:.4g}'
            horizon = f', horizon {design.horizon:g} s' if design.horizon else ''
            lines += ['', f'best design: candidate {design.candidate_id} (generation '
                          f'{design.generation}{horizon}), {fitness} ({objectives})']
            for name, value, unit, *_ in self.best_parameters():
                lines.append(f'  {name:<40} {value:>12.6g} {unit}')
        if self.elites:
            lines += ['', self.archive_text()]
        if self.rig is not None:
            lines += ['', self.rig.text()]
        return '\n'.join(lines)

    def generation_table(self):
        generations = self.generations
        if not len(generations):
            return '(no generation finished)'
        count = len(generations)
        shown = np.unique(np.linspace(0, count - 1, min(count, MAX_TABLE_ROWS)).astype(int))
        names = self.names
        header = ['gen'] + [f'best {n}' for n in names] + [f'median {n}' for n in names] + [
            'best so far', 'evals']
        table = [header]
        for index in shown:
            structure = generations.structures[index]
            label = str(generations.generations[index])
            if structure and len(set(generations.structures)) > 1:
                label = 'x'.join(map(str, structure)) + ':' + label
            evaluations = generations.evaluations[index]
            table.append([label] + [f'{v:.4g}' for v in generations.best[index]]
                         + [f'{v:.4g}' for v in generations.median[index]]
                         + [f'{generations.best_fitness[index]:.4g}',
                            '' if evaluations != evaluations else str(int(evaluations))])
        return aligned_table(table)


def racing_facts(record):
    """
    Return [('racing', text)]: the rollouts a raced run ran and saved, else [].

    A raced run's summaries record the worlds each told candidate met (core.search.racing);
    the rollouts saved are the worlds the candidates stopped early did not meet.
    """
    met = records.told_worlds(record)
    if not met:
        return []
    ran, whole, stopped = records.raced_rollouts(met)
    return [('racing', f'{ran} of {whole} rollouts run ({stopped} of {len(met)} candidates '
                       f'stopped early: {1 - ran / whole:.1%} of the rollouts saved)')]
