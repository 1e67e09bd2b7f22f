"""
The campaign: the paper's experiments and our levers, run, measured and tabulated.

Its modules (this face imports none of them):

- `experiment`: what an experiment is (Configuration, Budget, Experiment), its seeds and a
  configuration's task text; `registry` and `experiments/`: one module per experiment,
  registered by name (`experiments.EXPERIMENTS`); `shared`: configurations several of them run;
- `folders`: a campaign folder's layout (its runs' bags, campaign.json, the cached measures);
- `measures`: a finished run's design measured on unseen worlds (core.experiments.measures);
- `tables`, `figures`, `results`: an experiment's tables and figures from its measures;
- `bands`, `rates`: read a campaign folder back (`reproduce --bands`, `reproduce --rates`).

Above core, the bag room and analysis (it reads runs with analysis.records), below the
commands: `hand-codesign reproduce` (commands/reproduce.py) runs the campaign's processes.
"""
