"""Evaluation: one grouped cross-validation engine (folds by object) run on task values, and the
interval statistics of the study."""
