"""NumPy-only core: particle belief, likelihoods, retained sets, executors."""
