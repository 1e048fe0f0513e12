"""The learning side: LS-SVM regression, kernels, chaos PSO tuning, intervals, physics baselines and the drift model."""
