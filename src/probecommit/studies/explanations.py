"""Why our numbers differ from the paper's, per table (shown in REPRODUCTION.md).

Written after reading our frozen results. Each names a likely cause; none was
acted on by changing a parameter.
"""

EXPLANATIONS: dict[str, str] = {
    "scan": (
        "Matches by construction: the chamfer width is the one scene parameter the paper omits, set so the "
        "*scanned* flip lands at hg + 0.905 mm (docs/decisions.md). The scan then measures it independently."
    ),
    "cover": (
        "Following the paper's procedure, our search on our 24 development instances picked a different subset; "
        "the paper's schedule ranks 3rd (the top three differ by 2 of 96 development episodes), so the choice is "
        "noisy at this sample size. We froze our own winner, as the procedure says."
    ),
    "table_insertion": (
        "Blind rows agree within their intervals. Probed rows fail more than the paper's because our frozen "
        "schedule, the development-set winner, generalizes worse to Splits A and B than the paper's schedule: "
        "the selection on 24 instances overfits (see the cover-schedule note). The margin search lands lower "
        "(gamma 0.60 vs 0.74) because our calibration split's scenario score is less optimistic (see the audit). "
        "t_5 (cover) is 0.68 vs 0.42: more of our calibration instances need most of the mass to cover the truth."
    ),
    "table_audit": (
        "The trend is the paper's: escape rises and coverage falls with the budget, and optimism grows. Our "
        "original audit is milder (escape 0.10 vs 0.17 at k = 8, optimism +0.19 vs +0.31); we could not "
        "attribute this to one cause (candidates: resampling and jitter details the paper leaves implicit, and "
        "our tap that reads strictly top or floor). Calibrated cluster coverage stays near 0.57-0.60 at k >= 3 "
        "instead of 0.80: our fixed-budget thresholds land exactly on the zero-weight plateau (t_k = 1.000), "
        "the exception the paper names. Because fewer of our calibration instances escape the hull, the "
        "ranked score at q = ceil(0.8 (M + 1)) is a plateau score s = 1; at t = 1 the retained prefix stops "
        "short of the zero-weight particles, so s <= t does not imply coverage there. Coverage is reported on "
        "the sets as constructed, as in the paper. The budget-simultaneous threshold (1.011) is above the "
        "plateau and engages the grown set."
    ),
    "table_testc": (
        "The paper's pattern reproduces: the correction removes every escape, restores coverage to 1.000 and "
        "optimism to about zero, and cuts random k = 8 failure from 0.41 to 0.10 on instances drawn after the "
        "correction froze. Our old model escapes a little more on Test C than on Split B; cover-schedule rows "
        "differ with our schedule (see above)."
    ),
    "table_faults": (
        "Every class moves the way the paper reports except particle impoverishment, which in our harness "
        "neither raises escape much nor costs failure (paired +0.003): with 128 particles and no jitter our "
        "binary taps still leave enough copies near the truth. The boundary fault costs less than in the paper "
        "(0.30 vs 0.38) for the same reason the original audit is milder. Surprise AUCs are lower (0.56-0.57)."
    ),
    "robust": (
        "Tuning on the development instances chose T = 16 (the paper: 1) and eps = 0.05 (paper: 0.01); the "
        "development failures of the candidates differ by one or two episodes, so these choices are noisy. "
        "The paper's conclusion holds: the mixture and rejuvenation cut support escape but do not reduce "
        "failure (paired +0.018 and +0.023), and optimism stays positive. Unlike the paper, the mixture costs "
        "nothing when the model is right (0.107 -> 0.107)."
    ),
    "resplits": (
        "Failure across re-splits (0.317 +- 0.027) matches the paper's spread (0.328 +- 0.025). The calibrated "
        "level is lower and varies less, and the margin is optimistic in fewer splits (36% vs 64%), consistent "
        "with our less optimistic scenario score."
    ),
    "gates": (
        "The thresholds agree closely (1.016/1.011 vs 1.004/1.018 for the original model; 0.050 vs 0.046 for "
        "the corrected one on Test C). The gates' ranking differs: in our run the raw signal's committed pool "
        "holds escaped episodes at a lower rate than the pool it rejects (31/230 vs 29/154), while the adjusted "
        "signal's holds them at a higher rate (42/230 vs 18/154); the paper reports the raw gate retaining four "
        "times the rejected rate. Selection still re-creates optimism: every deployable gate claims less "
        "failure at commit than it realizes."
    ),
}
