"""The experiments: each runs learners through the evaluation and writes its result files
(training, ablation, power, perception effect, candidate scores, RL selector, benchmark, study)."""
