#!/usr/bin/python3
"""Two reliefs of a face's reflected pressure against the references of issue 16 (docs/accuracy.md,
"Clearing"): UFC 3-340-02's linear relief over tc = 4S/((1 + S/G) U), which spall uses, and the
acoustic relief of a rigid half-plane (Hudson 1955), each edge's taken separately and summed.

Usage: /usr/bin/python3 tools/clearing_models.py [path/to/spall]

The acoustic relief: a plane step wave struck head-on on a rigid half-plane. The field is
self-similar in s = d/(c t) (d from the edge, t since the reflection); Busemann's map
rho = (1 - sqrt(1 - s^2))/s makes it harmonic in the unit disc, and unfolding the plate's slit by
a square root leaves a Dirichlet problem whose harmonic measure gives, on the lit face, the part
of the reflected excess still there: (2/pi) asin(sqrt(s)) for s < 1, all of it before the edge's
signal arrives. `check_closed_form` compares it with the disc's Poisson integral.
"""
import json
import math
import subprocess
import sys

P0_PA, C0_MS = 101325.0, 340.2  # the CFD reference's air: gamma 1.4 at 288 K


def impulse_fraction(b):
    """Friedlander impulse / (Ps T+) for decay b (blast-data.md §3)."""
    return 1 / b - (1 - math.exp(-b)) / b**2


def decay_for(fraction):
    lo, hi = 1e-6, 60.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if impulse_fraction(mid) > fraction else (lo, mid)
    return 0.5 * (lo + hi)


def reflected_sound_speed_ms(ps_pa, pr_pa):
    """Sound speed behind the reflected shock: two Rankine-Hugoniot temperature jumps (gamma 1.4)."""
    def jump(ratio):
        return ratio * (6 + ratio) / (1 + 6 * ratio)
    incident = 1 + ps_pa / P0_PA
    return C0_MS * math.sqrt(jump(incident) * jump((P0_PA + pr_pa) / (P0_PA + ps_pa)))


def acoustic_kept(s):
    return 1.0 if s >= 1 else (2 / math.pi) * math.asin(math.sqrt(s))


def check_closed_form():
    """Largest gap between the closed form and the Poisson integral of the unfolded disc."""
    worst = 0.0
    for s in (0.999, 0.9, 0.5, 0.1, 0.01):
        rho = (1 - math.sqrt(1 - s * s)) / s
        z = complex(-math.sqrt(rho), 0)
        n, total = 20000, 0.0
        for k in range(n):
            a = -math.pi + (k + 0.5) * 2 * math.pi / n
            data = 0.0 if abs(a) < math.pi / 4 else (1.0 if abs(a) < 3 * math.pi / 4 else 2.0)
            total += data * (1 - abs(z) ** 2) / abs(complex(math.cos(a), math.sin(a)) - z) ** 2
        worst = max(worst, abs(total / n - 1 - acoustic_kept(s)))
    return worst


def front_impulse_pa_s(wave, faces, relief, steps=4000):
    """Mean front impulse over the faces (each a list of distances to its free edges, m)."""
    dt, total = wave["T"] / steps, 0.0
    for i in range(steps):
        t = (i + 0.5) * dt
        shape = (1 - t / wave["T"])
        side_on = wave["ps"] * shape * math.exp(-wave["b"] * t / wave["T"])
        stagnation = side_on + 2.5 * side_on**2 / (side_on + 7 * P0_PA)
        reflected = wave["pr"] * shape * math.exp(-wave["br"] * t / wave["T"])
        for edges in faces:
            total += (stagnation + relief(edges, t) * (reflected - stagnation)) * dt
    return total / len(faces)


def wave_from(ps, T, i_s, pr, ir, u):
    return {"ps": ps, "T": T, "b": decay_for(i_s / (ps * T)), "pr": pr, "br": decay_for(ir / (pr * T)), "U": u}


def kingery_bulmash(spall, kg, m, burst):
    j = json.loads(subprocess.check_output([spall, "blast", "--tnt-kg", str(kg), "--distance-m", str(m), "--burst", burst, "--json"]))
    return wave_from(j["peak_overpressure_Pa"], j["positive_duration_s"], j["positive_impulse_Pa_s"],
                     j["reflected_pressure_Pa"], j["reflected_impulse_Pa_s"], j["shock_speed_m_s"])


def reliefs(wave, smaller_m, larger_m):
    tc = 4 * smaller_m / ((1 + smaller_m / larger_m) * wave["U"])
    c = reflected_sound_speed_ms(wave["ps"], wave["pr"])
    ufc = lambda edges, t: max(0.0, 1 - t / tc)
    acoustic = lambda edges, t: max(0.0, 1 - sum(1 - acoustic_kept(d / (c * t)) for d in edges))
    return {"UFC linear": ufc, "acoustic": acoustic}


def wall_ratio(wave, height_m):
    """A long wall on the ground (its image edge at height + z) against a 3.5 m wall."""
    rows = [0.05 + 0.1 * k for k in range(int(round(height_m / 0.1)))]
    low = [[height_m - z, height_m + z] for z in rows]
    tall = [[3.5 - z, 3.5 + z] for z in rows]
    tall_reliefs = reliefs(wave, 3.5, 10.0)
    return {name: front_impulse_pa_s(wave, low, relief) / front_impulse_pa_s(wave, tall, tall_reliefs[name])
            for name, relief in reliefs(wave, height_m, 10.0).items()}


def main():
    spall = sys.argv[1] if len(sys.argv) > 1 else "build/spall"
    print(f"closed form against the Poisson integral: largest gap {check_closed_form():.1e}")
    cfd = wave_from(151e3, 1.44e-3, 72.8, 486e3, 256.0, C0_MS * math.sqrt(1 + 6 * 151e3 / (7 * P0_PA)))
    tnt = kingery_bulmash(spall, 0.365, 2.0, "surface")
    for label, wave in (("the CFD's own wave", cfd), ("Kingery-Bulmash, 0.365 kg surface burst at 2 m", tnt)):
        for name, ratio in wall_ratio(wave, 0.5).items():
            print(f"0.5 m wall / tall wall, {label}, {name}: {ratio:.3f} (CFD 0.875)")
    cube = kingery_bulmash(spall, 10.0, 10.0, "free-air")
    faces = [[u, 0.4 - u, v, 0.4 - v] for u in (0.05, 0.15, 0.25, 0.35) for v in (0.05, 0.15, 0.25, 0.35)]
    for name, relief in reliefs(cube, 0.2, 0.2).items():
        print(f"0.4 m cube 10 m from 10 kg, front face, {name}: {front_impulse_pa_s(cube, faces, relief) * 0.16:.2f} N s "
              "(UFC by hand 20.17)")


if __name__ == "__main__":
    main()
