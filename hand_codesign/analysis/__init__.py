"""Reading bags of runs: reports, replays, robustness studies and design export."""
