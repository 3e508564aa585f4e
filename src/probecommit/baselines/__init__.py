"""Learned baselines compared with the pipeline (the GRU of the paper's Sec. V-A)."""
