"""The estimators, each with the scikit-learn API: the model registry, the training-free
baselines, the torch MLPs, the lambdarank ranker, and how fitted models are saved without pickle."""
