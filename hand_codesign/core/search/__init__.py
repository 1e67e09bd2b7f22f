"""
The search room: ask/tell optimizers, their registry, and the searches built from them.

Modules: optimizers (CMA-ES, MO-CMA-ES and their base), pycma (pycma, quietly), restarts
(IPOP/BIPOP-CMA-ES), quality_diversity (CMA-MAE, CMA-ME), factory (the name-to-class registry
above them: make_optimizer), hierarchy (Fig. 1's bottom-up search), stages (two stages),
horizon (growing horizons), resampling (worlds drawn each generation), search (a run's whole
search, one batch at a time), resume (rebuilding it from a bag's evaluations). Imports core's
root, the task and sim rooms; never run, rig or experiments.
"""
