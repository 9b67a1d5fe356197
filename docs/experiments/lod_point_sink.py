"""The steady state of split backward-Euler steps near a point sink (README "Time stepping",
26 Nov 2026). A 31 x 31 grid, zero outside, a unit sink at the centre cell: the true steady
state solves A u = S (5-point Laplacian). Stepping to a fixed point:
  LOD (the model's implicit step, sink moved into the gel before the step):
      u <- (I - rAy)^-1 (I - rAx)^-1 (u - rS)
  delta form (Douglas), sink in the right-hand side:
      u <- u + (I - rAy)^-1 (I - rAx)^-1 (r A u - r S)
  delta form, sink moved into the gel before the step:
      v = u - rS;  u <- v + (I - rAy)^-1 (I - rAx)^-1 (r A v)
Prints each fixed point over the true steady state at the sink and 1, 2, 4 cells away.
Plain Python, no packages: python3 docs/experiments/lod_point_sink.py (about a minute)."""

n = 31
c = n // 2


def tri(rhs, r):
    """(1 + 2r) x_i - r x_{i-1} - r x_{i+1} = rhs_i, zero outside (Thomas algorithm)."""
    m = len(rhs)
    cp, dp = [0.0] * m, [0.0] * m
    b, a = 1 + 2 * r, -r
    cp[0], dp[0] = a / b, rhs[0] / b
    for i in range(1, m):
        den = b - a * cp[i - 1]
        cp[i], dp[i] = a / den, (rhs[i] - a * dp[i - 1]) / den
    x = [0.0] * m
    x[-1] = dp[-1]
    for i in range(m - 2, -1, -1):
        x[i] = dp[i] - cp[i] * x[i + 1]
    return x


def sweep(u, r):
    u = [tri(row, r) for row in u]
    cols = [tri([u[j][i] for j in range(n)], r) for i in range(n)]
    return [[cols[i][j] for i in range(n)] for j in range(n)]


def lap(u):
    g = lambda j, i: u[j][i] if 0 <= i < n and 0 <= j < n else 0.0
    return [[g(j, i - 1) + g(j, i + 1) + g(j - 1, i) + g(j + 1, i) - 4 * u[j][i]
             for i in range(n)] for j in range(n)]


def fixed_point(step):
    u = [[0.0] * n for _ in range(n)]
    for _ in range(20000):
        v = step(u)
        d = max(abs(v[j][i] - u[j][i]) for j in range(n) for i in range(n))
        u = v
        if d < 1e-12:
            break
    return u


def true_steady():
    u = [[0.0] * n for _ in range(n)]
    for _ in range(4000):  # SOR on A u = S
        for j in range(n):
            for i in range(n):
                s = sum(u[jj][ii] for jj, ii in ((j, i - 1), (j, i + 1), (j - 1, i), (j + 1, i))
                        if 0 <= ii < n and 0 <= jj < n)
                rhs = 1.0 if (i == c and j == c) else 0.0
                u[j][i] += 1.9 * ((s - rhs) / 4 - u[j][i])
    return u


def lod(r):
    def step(u):
        v = [row[:] for row in u]
        v[c][c] -= r
        return sweep(v, r)
    return step


def delta(r):
    def step(u):
        a = lap(u)
        rhs = [[r * a[j][i] for i in range(n)] for j in range(n)]
        rhs[c][c] -= r
        w = sweep(rhs, r)
        return [[u[j][i] + w[j][i] for i in range(n)] for j in range(n)]
    return step


def delta_sink_in_gel(r):
    def step(u):
        v = [row[:] for row in u]
        v[c][c] -= r
        a = lap(v)
        w = sweep([[r * a[j][i] for i in range(n)] for j in range(n)], r)
        return [[v[j][i] + w[j][i] for i in range(n)] for j in range(n)]
    return step


ut = true_steady()
at = lambda u: [round(u[c][c + d] / ut[c][c + d], 4) for d in (0, 1, 2, 4)]
for r in (0.3, 1, 3, 10):
    print(f"r = D dt/h^2 = {r}: LOD {at(fixed_point(lod(r)))}, delta form {at(fixed_point(delta(r)))}")
for r in (1, 3):
    print(f"r = {r}: delta form, sink moved into the gel first {at(fixed_point(delta_sink_in_gel(r)))}")
