#!/usr/bin/env python3
"""The peer of bench/arx_bench.cpp: the same ARX (na = 1, nb = 3 per input with the
instantaneous term, intercept) fitted by statsmodels' AutoReg with the lagged inputs as
exogenous regressors. Prints JSON: seconds (median of REPS), theta and u in probeloop's
naming (a1 = minus the AR coefficient, A(q) = 1 + a1 q^-1)."""
import json, sys, time
import numpy as np
import pandas as pd
import statsmodels
from statsmodels.tsa.ar_model import AutoReg

data = pd.read_csv(sys.argv[1])
reps = int(sys.argv[2]) if len(sys.argv) > 2 else 51
r = data.shape[1] - 1
cols = {}
for i in range(r):
    for lag in range(3):
        cols[f"b[u{i + 1}][lag {lag}]"] = data[f"u{i + 1}"].shift(lag)
# Rows k = 2 .. N-1 as in probeloop (the first two samples are history for lag 2): AutoReg
# holds back its first row (lag 1), so the series start at k = 1; that row's lag-2 input is
# unknown and only held back, so it is filled with 0.
exog = pd.DataFrame(cols).iloc[1:].fillna(0.0).reset_index(drop=True)
endog = data["y"].iloc[1:].reset_index(drop=True)
times = []
for _ in range(reps):
    t0 = time.perf_counter()
    res = AutoReg(endog, lags=1, trend="c", exog=exog, old_names=False).fit()
    times.append(time.perf_counter() - t0)
times.sort()
p = res.params
# AutoReg's sigma^2 is SSR / n; probeloop's (like OLS) SSR / (n - parameters): rescale the
# standard errors so that both state the same thing.
se = res.bse * np.sqrt(res.nobs / (res.nobs - len(p)))
theta = {"a1": -p["y.L1"], "c": p["const"]}
u = {"a1": se["y.L1"], "c": se["const"]}
for name in cols:
    theta[name] = p[name]
    u[name] = se[name]
print(json.dumps({"peer": "statsmodels " + statsmodels.__version__ + " AutoReg", "seconds": times[len(times) // 2],
                  "theta": theta, "u": u}))
