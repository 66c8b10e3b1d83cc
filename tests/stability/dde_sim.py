"""Independent check: direct time integration of the 1-DOF milling delay equation.

    m ẍ + c ẋ + k x = −a h(t) (x(t) − x(t − τ)),
    h(t) = Σ_j g_j sin φ_j (K_t cos φ_j + K_n sin φ_j)

Classical fixed-step RK4 with a history buffer: τ is an integer number K of
steps, the delayed value at the half steps is the mean of its two neighbours,
and h(t) is evaluated pointwise from the tooth angles (no averaging, no
semi-discretization). Written independently of jointdb.stability.
"""

import math


def simulate_growth(m, c, k, kt, kn, n_teeth, phi_st, phi_ex, rpm, depth, periods=120, steps=256):
    tau = 60.0 / (n_teeth * rpm)
    dt = tau / steps
    omega = 2 * math.pi * rpm / 60.0

    def h(t):
        total = 0.0
        for j in range(n_teeth):
            phi = (omega * t + 2 * math.pi * j / n_teeth) % (2 * math.pi)
            if phi_st < phi < phi_ex:
                total += math.sin(phi) * (kt * math.cos(phi) + kn * math.sin(phi))
        return total

    # h is tau-periodic: tabulate on full and half steps
    hf = [h(i * dt) for i in range(steps)]
    hh = [h((i + 0.5) * dt) for i in range(steps)]
    hist = [0.0] * steps  # x at t - tau .. t - dt (ring buffer, index = step mod steps)
    x, v = 1e-6, 0.0
    amp = []
    period_max = 0.0
    total = periods * steps
    for n in range(total):
        i = n % steps
        xd0 = hist[i]  # x(t - tau)
        xd1 = hist[(i + 1) % steps]  # x(t + dt - tau), stored one period ago
        xdm = 0.5 * (xd0 + xd1)

        def acc(xx, vv, hv, xd):
            return (-c * vv - k * xx - depth * hv * (xx - xd)) / m

        a1 = acc(x, v, hf[i], xd0)
        x2, v2 = x + 0.5 * dt * v, v + 0.5 * dt * a1
        a2 = acc(x2, v2, hh[i], xdm)
        x3, v3 = x + 0.5 * dt * v2, v + 0.5 * dt * a2
        a3 = acc(x3, v3, hh[i], xdm)
        x4, v4 = x + dt * v3, v + dt * a3
        a4 = acc(x4, v4, hf[(i + 1) % steps], xd1)
        hist[i] = x
        x = x + dt / 6 * (v + 2 * v2 + 2 * v3 + v4)
        v = v + dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        period_max = max(period_max, abs(x))
        if i == steps - 1:
            amp.append(period_max)
            period_max = 0.0
    # growth per period, fitted over the second half of the run
    half = amp[len(amp) // 2 :]
    return (half[-1] / half[0]) ** (1.0 / (len(half) - 1)), amp
