"""Speed of the core: prints figures and ratios, asserts nothing.

    python benchmarks/core_speed.py

Targets on the 2-core machine, one process: a 100 × 100 (amplitude × frequency) stiffness map
≤ 2 ms; 3-slice map ≤ 50 ms; continuum map ≤ 200 ms; a 10⁶-sample history ≤ 3 s. Each is
printed beside the thesis' time-domain route for the same work (a few points measured, then
scaled), as a ratio.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from core import PAPER_B, bushing, force_history, slices, stiffness, strain_factor
from core.material import equivalent_modulus, equivalent_modulus_time_domain, fractional_stress


def timed(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def uncached_map(slices_arg, f, x):
    bushing._stiffness_cached.cache_clear()
    return stiffness(PAPER_B, f, x, slices=slices_arg)


def bulk_map(design, f, x):
    """The map of a design with a bulk modulus, uncached, and how many µ* evaluations per point
    its solve for the rubber's strain amplitude made (the last one, at the solution, included)."""
    calls = []
    modulus = bushing.modulus_function(design)

    def counting(frequency_hz, strain):
        calls.append(np.size(strain))
        return modulus(frequency_hz, strain)

    s, c = bushing.factors(design)
    bushing.equivalent_stiffness(counting, s, c, f[None, :], x[:, None], bushing.bulk_correction(design))
    return len(calls)


def modulus_evaluations_per_point(slices_arg, f, x):
    """How many µ(ε̂) evaluations per grid point and layer the series solver makes."""
    calls = []
    original = slices.solve_series

    def counting(nodes, drive, modulus, strain_guess, **kw):
        def m(eps):
            calls.append(eps.size)
            return modulus(eps)

        return original(nodes, drive, m, strain_guess, **kw)

    bushing.solve_series = counting
    try:
        uncached_map(slices_arg, f, x)
    finally:
        bushing.solve_series = original
    return sum(calls) / (f.size * x.size)


def main():
    f = np.linspace(1.0, 100.0, 100)
    x = np.geomspace(1e-5, 1e-3, 100)  # 0.01–1 mm, Paper B
    c = strain_factor(PAPER_B.geometry, "axial")

    # time-domain route: a few points, per-point cost
    rng = np.random.default_rng(0)
    pts = [(float(rng.choice(f)), float(rng.choice(x))) for _ in range(8)]
    t0 = time.perf_counter()
    for fi, xi in pts:
        equivalent_modulus_time_domain(PAPER_B.material, fi, c * xi)
    td_point = (time.perf_counter() - t0) / len(pts)

    print(f"time-domain route: {td_point * 1e3:.1f} ms per (frequency, amplitude) point "
          f"(mean of {len(pts)} points)\n")
    print(f"{'work':<40} {'measured':>12} {'target':>10} {'time-domain est.':>18} {'ratio':>10}")

    def row(name, seconds, target, reference):
        print(f"{name:<40} {seconds * 1e3:>9.2f} ms {target:>10} {reference:>16.1f} s {reference / seconds:>10.0f}")

    single = timed(lambda: uncached_map(1, f, x), 30)
    row("100×100 map, single modulus", single, "≤ 2 ms", td_point * f.size * x.size)
    cached = timed(lambda: stiffness(PAPER_B, f, x), 200)
    print(f"{'  same map again (from the cache)':<40} {cached * 1e6:>9.1f} µs")

    # a thin wall (the b/a 1.2, L/(b − a) 9.9) with K = 1.9 GPa: µ* at the rubber's own
    # strain amplitude, solved at every point at once; CPU time against the same map without K
    thin = PAPER_B.replace(inner_radius=0.02, outer_radius=0.024, length=0.0396).in_mode("radial")
    xr = thin.drive(np.geomspace(1e-5, 1e-2, 100))
    cpu = {}
    for name, d in (("without K", thin), ("K 1.9 GPa", thin.replace(bulk_modulus=1.9e9))):
        t0 = time.process_time()
        for _ in range(10):
            bushing._stiffness_cached.cache_clear()
            stiffness(d, f, xr)
        cpu[name] = (time.process_time() - t0) / 10
    evals = bulk_map(thin.replace(bulk_modulus=1.9e9), f, xr)
    print(f"{'100×100 radial thin-wall map, CPU':<40} {cpu['without K'] * 1e3:>9.2f} ms without K, "
          f"{cpu['K 1.9 GPa'] * 1e3:.2f} ms with K 1.9 GPa ({cpu['K 1.9 GPa'] / cpu['without K']:.1f}×; "
          f"{evals} µ* evaluations of the whole grid)")

    for name, arg, target, nodes in (
        ("100×100 map, 3 slices", 3, "≤ 50 ms", 3),
        ("100×100 map, continuum", "continuum", "≤ 200 ms", slices.continuum_node_count(PAPER_B.geometry, "axial")),
    ):
        seconds = timed(lambda arg=arg: uncached_map(arg, f, x), 7)
        evals = modulus_evaluations_per_point(arg, f, x)  # layer-evaluations per point
        row(name, seconds, target, td_point * f.size * x.size * evals)
        print(f"{'':<40} ({nodes} layers, {evals / nodes:.0f} modulus evaluations per layer)")

    # histories: a multibody-like drive (a few harmonics, smooth) and a worst case (noise:
    # a reversal at almost every sample)
    n, dt = 1_000_000, 1e-4
    t = dt * np.arange(n)
    smooth = 1e-3 * (np.sin(2 * np.pi * 3 * t) + 0.3 * np.sin(2 * np.pi * 17 * t + 1) + 0.1 * np.sin(2 * np.pi * 41 * t))
    noisy = smooth + 2e-5 * rng.standard_normal(n)
    # reference: the Grünwald–Letnikov sum done directly, O(N²), measured on 20 000 samples
    m = 20_000
    w_direct = time.perf_counter()
    from core.material import grunwald_weights

    w = grunwald_weights(m, PAPER_B.material.fractional_order)
    eps = smooth[:m]
    direct = np.array([w[: k + 1] @ eps[k::-1] for k in range(m)])
    w_direct = time.perf_counter() - w_direct
    assert np.allclose(direct * PAPER_B.material.fractional_coefficient * dt ** -PAPER_B.material.fractional_order,
                       fractional_stress(eps, dt, PAPER_B.material.fractional_coefficient, PAPER_B.material.fractional_order))
    direct_est = w_direct * (n / m) ** 2
    for name, signal in (("10⁶-sample history, smooth drive", smooth), ("10⁶-sample history, noisy drive", noisy)):
        seconds = timed(lambda signal=signal: force_history(PAPER_B, signal, dt), 3)
        reversals = int(np.count_nonzero(np.diff(np.sign(np.diff(signal)))))
        print(f"{name:<40} {seconds * 1e3:>9.0f} ms {'≤ 3 s':>10} {direct_est:>16.0f} s {direct_est / seconds:>10.0f}"
              f"   ({reversals} reversals)")
    # through a bulk spring in series (the thin wall, radial, K 1.9 GPa): the first 10⁵
    # samples of the same drives, CPU time against the same history without K
    m = 100_000
    for name, signal in (("10⁵ samples through a bulk spring, smooth", smooth), ("  the same, noisy", noisy)):
        cpu = []
        for d in (thin, thin.replace(bulk_modulus=1.9e9)):
            t0 = time.process_time()
            force_history(d, signal[:m], dt)
            cpu.append(time.process_time() - t0)
        print(f"{name:<40} {cpu[1] * 1e3:>9.0f} ms CPU (without K {cpu[0] * 1e3:.0f} ms: {cpu[1] / cpu[0]:.0f}×)")
    print("\n(history reference: the direct O(N²) Grünwald–Letnikov sum, measured on 20 000 samples"
          " and scaled by N²)")
    _ = equivalent_modulus  # the analytic route used by the maps


if __name__ == "__main__":
    main()
