"""Statistics for comparing two Monte Carlo renderers: Welch t-tests on pixel
and block means with a Šidák correction. numpy only (no scipy).

Conventions: every array of "passes" has shape (K, H, W, C): K independent
renders (distinct seeds) of the same image. The mean over passes estimates the
pixel value; the sample variance over passes divided by K estimates the
variance of that mean.
"""
import math

import numpy as np

# ---------------------------------------------------------------------------
# Special functions
# ---------------------------------------------------------------------------

_LGAMMA = np.vectorize(math.lgamma, otypes=[np.float64])


def _betacf(a, b, x, iters=300):
    """Continued fraction of the incomplete beta function (modified Lentz),
    vectorised over arrays a, b, x of one shape. Converges quickly for
    x < (a + 1) / (a + b + 2)."""
    tiny = 1e-300
    qab = a + b
    qap = a + 1.0
    qam = a - 1.0
    c = np.ones_like(x)
    d = 1.0 - qab * x / qap
    d = np.where(np.abs(d) < tiny, tiny, d)
    d = 1.0 / d
    h = d.copy()
    done = np.zeros(x.shape, dtype=bool)
    for m in range(1, iters + 1):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = np.where(np.abs(d) < tiny, tiny, d)
        c = 1.0 + aa / c
        c = np.where(np.abs(c) < tiny, tiny, c)
        d = 1.0 / d
        h = np.where(done, h, h * d * c)
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = np.where(np.abs(d) < tiny, tiny, d)
        c = 1.0 + aa / c
        c = np.where(np.abs(c) < tiny, tiny, c)
        d = 1.0 / d
        delta = d * c
        h = np.where(done, h, h * delta)
        done |= np.abs(delta - 1.0) < 1e-15
        if done.all():
            break
    return h


def betainc_reg(a, b, x):
    """Regularised incomplete beta function I_x(a, b), vectorised."""
    a, b, x = np.broadcast_arrays(np.asarray(a, np.float64),
                                  np.asarray(b, np.float64),
                                  np.asarray(x, np.float64))
    a = a.copy(); b = b.copy(); x = np.clip(x, 0.0, 1.0)
    out = np.empty(x.shape, np.float64)
    if out.size == 0:
        return out
    lbeta = _LGAMMA(a + b) - _LGAMMA(a) - _LGAMMA(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        front = np.exp(lbeta + a * np.log(x) + b * np.log1p(-x))
    front = np.where((x <= 0.0) | (x >= 1.0), 0.0, front)
    direct = x < (a + 1.0) / (a + b + 2.0)
    # Direct continued fraction where it converges, else the symmetry
    # I_x(a, b) = 1 - I_{1-x}(b, a).
    xa = np.where(direct, x, 1.0 - x)
    aa = np.where(direct, a, b)
    bb = np.where(direct, b, a)
    cf = _betacf(aa, bb, xa)
    val = front * cf / aa
    out = np.where(direct, val, 1.0 - val)
    out = np.where(x <= 0.0, 0.0, out)
    out = np.where(x >= 1.0, 1.0, out)
    return out


def t_two_sided_p(t, dof):
    """Two-sided p-value P(|T| >= |t|) of Student's t with (real) dof > 0.
    dof = inf gives the normal distribution (math.erfc)."""
    t = np.abs(np.asarray(t, np.float64))
    dof = np.broadcast_to(np.asarray(dof, np.float64), t.shape)
    p = np.empty(t.shape, np.float64)
    normal = ~np.isfinite(dof)
    if normal.any():
        p[normal] = np.vectorize(math.erfc, otypes=[np.float64])(t[normal] / math.sqrt(2.0))
    st = ~normal
    if st.any():
        tt, nu = t[st], dof[st]
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            x = nu / (nu + tt * tt)
        x = np.where(np.isinf(tt), 0.0, x)
        p[st] = betainc_reg(nu / 2.0, 0.5, x)
    return np.clip(p, 0.0, 1.0)


def sidak_alpha(alpha, n_tests):
    """Per-test level giving family-wise error alpha over n_tests tests
    (Šidák: exact for independent tests, conservative for two-sided Gaussian
    tests with any correlation)."""
    if n_tests <= 0:
        return alpha
    return -math.expm1(math.log1p(-alpha) / n_tests)


def t_critical(alpha, dof):
    """|t| above which a two-sided test at level alpha rejects (bisection)."""
    lo, hi = 0.0, 1.0
    while t_two_sided_p(hi, dof) > alpha:
        hi *= 2.0
        if hi > 1e12:
            return float("inf")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if t_two_sided_p(mid, dof) > alpha:
            lo = mid
        else:
            hi = mid
    return hi


# ---------------------------------------------------------------------------
# Moments of passes
# ---------------------------------------------------------------------------

def pass_moments(passes):
    """(mean, variance of the mean, K) of an array of passes (K, ...)."""
    x = np.asarray(passes, np.float64)
    k = x.shape[0]
    mean = x.mean(axis=0)
    if k < 2:
        raise ValueError("need at least 2 passes to estimate a variance")
    var = x.var(axis=0, ddof=1) / k
    return mean, var, k


def block_sum(img, b):
    """Sum over non-overlapping b x b blocks of the last-but-one two axes
    (..., H, W, C) -> (..., H//b, W//b, C); edge rows/columns that do not fill
    a block are dropped."""
    h, w = img.shape[-3], img.shape[-2]
    hb, wb = h // b, w // b
    x = img[..., :hb * b, :wb * b, :]
    shp = x.shape[:-3] + (hb, b, wb, b, x.shape[-1])
    return x.reshape(shp).sum(axis=(-4, -2))


def block_levels(h, w, sizes=(1, 4, 16)):
    """Block sizes to test: the given sizes that fit, plus the whole image."""
    out = [b for b in sizes if b <= min(h, w)]
    out.append(0)  # 0 = whole image
    return out


# ---------------------------------------------------------------------------
# The test
# ---------------------------------------------------------------------------

# Differences below these are treated as equal even where both variances are 0
# (e.g. a background pixel that is exactly the emitter's radiance in both).
EPS_REL = 1e-4
EPS_ABS = 1e-6


def welch(mean_a, var_a, dof_a, mean_b, var_b, dof_b):
    """Welch's t statistic and Welch-Satterthwaite degrees of freedom for
    the difference of two independent means with estimated variances."""
    var = var_a + var_b
    floor = (EPS_REL * np.maximum(np.abs(mean_a), np.abs(mean_b))) ** 2 + EPS_ABS ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = var_a ** 2 / dof_a + var_b ** 2 / dof_b
        nu = np.where(denom > 0, var * var / np.where(denom > 0, denom, 1.0),
                      min(dof_a, dof_b))
    nu = np.maximum(nu, min(dof_a, dof_b))  # Welch-Satterthwaite is >= min dof
    t = (mean_a - mean_b) / np.sqrt(np.maximum(var, floor))
    return t, nu


class LevelResult:
    def __init__(self, block, t, p, nu, n_tests, rejected, allowed):
        self.block = block          # block edge in pixels, 0 = whole image
        self.t = t                  # (Hb, Wb, C) t statistics
        self.p = p                  # (Hb, Wb, C) two-sided p-values
        self.nu = nu                # (Hb, Wb, C) degrees of freedom
        self.n_tests = n_tests
        self.rejected = rejected    # (Hb, Wb, C) bool
        self.allowed = allowed      # rejections tolerated at this level

    @property
    def n_rejected(self):
        return int(self.rejected.sum())

    @property
    def passed(self):
        return self.n_rejected <= self.allowed

    def name(self, h=None, w=None):
        return "image" if self.block == 0 else f"{self.block}x{self.block}"


class TestResult:
    def __init__(self, levels, alpha, alpha_test, tolerance):
        self.levels = levels
        self.alpha = alpha
        self.alpha_test = alpha_test
        self.tolerance = tolerance

    @property
    def passed(self):
        return all(l.passed for l in self.levels)

    @property
    def n_tests(self):
        return sum(l.n_tests for l in self.levels)

    def level(self, block):
        for l in self.levels:
            if l.block == block:
                return l
        return None

    def summary_rows(self):
        rows = []
        for l in self.levels:
            rows.append(dict(level=l.name(), tests=l.n_tests, rejected=l.n_rejected,
                             allowed=l.allowed, min_p=float(l.p.min()),
                             max_abs_t=float(np.abs(l.t).max()),
                             passed=l.passed))
        return rows


def compare_to_reference(cand_passes, ref_mean, ref_var, ref_k,
                         alpha=0.01, tolerance=0.0025, blocks=(1, 4, 16)):
    """Test H0: the candidate's expected image equals the reference's.

    cand_passes: (K, H, W, C) candidate passes (independent renders).
    ref_mean, ref_var: (H, W, C) reference mean and variance of that mean,
        from ref_k independent passes of an independent-sampler, box-filter
        render (pixels independent, so block variances add).
    alpha: family-wise significance level over all tests of all levels.
    tolerance: fraction of the tests of a level allowed to reject
        (floor(tolerance * n_tests)); as in Mitsuba's test_renders.py this
        absorbs the non-normal tails of single pixels at low spp.
    """
    cand = np.asarray(cand_passes, np.float64)
    k, h, w, c = cand.shape
    ref_mean = np.asarray(ref_mean, np.float64)
    ref_var = np.asarray(ref_var, np.float64)
    assert ref_mean.shape == (h, w, c), (ref_mean.shape, cand.shape)
    levels = block_levels(h, w, blocks)
    stats = []
    for b in levels:
        if b == 0:
            cb = cand.mean(axis=(1, 2))[:, None, None, :]
            n = h * w
            rm = ref_mean.sum(axis=(0, 1))[None, None, :] / n
            rv = ref_var.sum(axis=(0, 1))[None, None, :] / (n * n)
        elif b == 1:
            cb, rm, rv = cand, ref_mean, ref_var
        else:
            n = b * b
            cb = block_sum(cand, b) / n
            rm = block_sum(ref_mean, b) / n
            rv = block_sum(ref_var, b) / (n * n)
        cm, cv, _ = pass_moments(cb)
        t, nu = welch(cm, cv, k - 1, rm, rv, ref_k - 1)
        # NaN or infinite values (in a pass, hence in a mean or variance) are
        # rejections, never silent passes.
        t = np.where(np.isfinite(t), t, np.inf)
        nu = np.where(np.isfinite(nu), nu, min(k, ref_k) - 1)
        stats.append((b, t, nu))
    n_total = sum(t.size for _, t, _ in stats)
    alpha_test = sidak_alpha(alpha, n_total)
    out = []
    for b, t, nu in stats:
        p = t_two_sided_p(t, nu)
        rej = p < alpha_test
        allowed = int(math.floor(tolerance * t.size))
        out.append(LevelResult(b, t, p, nu, t.size, rej, allowed))
    return TestResult(out, alpha, alpha_test, tolerance)


def rel_mse(x, ref, eps=0.01):
    """relMSE = mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels."""
    x = np.asarray(x, np.float64)
    ref = np.asarray(ref, np.float64)
    return float(np.mean((x - ref) ** 2 / (ref * ref + eps)))
