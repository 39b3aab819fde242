"""Learning grip success from the twelve features: learners, evaluation, experiments, report."""
