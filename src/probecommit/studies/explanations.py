"""Why our numbers differ from the paper's, per table (shown in REPRODUCTION.md).

Written after reading our frozen results; each names a likely cause, never a tuned parameter.
"""

EXPLANATIONS: dict[str, str] = {}
