"""Recomputes every figure of `spall debris` from history.h5 with numpy, following the definitions
in docs/debris.md, and compares with debris.h5. Usage: check_debris.py OUTDIR"""
import math, sys
import h5py, numpy as np

out = sys.argv[1]
h = h5py.File(out + "/history.h5", "r")
d = h5py.File(out + "/debris.h5", "r")
G = 9.80665
t = h["frames/time_s"][:]
off = h["frames/body_offset"][:]
ids, parents = h["bodies/id"][:], h["bodies/parent_id"][:]
pos, vel = h["bodies/position_m"][:], h["bodies/linear_velocity_m_s"][:]
tnt = h["charges/tnt_kg"][:]
origin = (h["charges/position_m"][:] * tnt[:, None]).sum(0) / tnt.sum()
assert np.allclose([d.attrs["origin_x_m"], d.attrs["origin_y_m"], d.attrs["origin_z_m"]], origin)
parent = dict(zip(ids.tolist(), parents.tolist()))
rows = [dict(zip(ids[off[f]:off[f + 1]].tolist(), range(off[f], off[f + 1]))) for f in range(len(t))]
last = rows[-1]
frag = d["fragments"]
assert sorted(last) == frag["id"][:].tolist()
mass = h["bodies/mass_kg"][:]
anchored = h["bodies/anchored"][:]
birth = {}
for r in rows:
    for b, row in r.items():
        birth.setdefault(b, row)
stayed = {f: bool(anchored[last[f]]) or np.hypot(*(pos[last[f]] - pos[birth[f]])[:2]) < d.attrs["stay_distance_m"] for f in last}


def flight(fid):
    lineage = [fid]
    while parent.get(lineage[-1], -1) >= 0:
        lineage.append(parent[lineage[-1]])
    track = [next((r[b] for b in lineage if b in r), None) for r in rows]
    m = mass[last[fid]]
    speed = [None if r is None else np.linalg.norm(vel[r]) for r in track]
    launch = next((f for f, s in enumerate(speed) if s is not None and s >= d.attrs["launch_speed_m_s"]), None)
    if launch is None:
        return None
    peak = 0.5 * m * speed[launch] ** 2
    for f in range(launch + 1, len(t)):
        a, b = track[f - 1], track[f]
        if a is None or b is None:
            continue
        if vel[a][2] < -0.5 * G * (t[f] - t[f - 1]) and vel[b][2] > 0.5 * vel[a][2]:
            return t[launch], peak, (t[f], 0.5 * m * speed[f - 1] ** 2, pos[b])
        peak = max(peak, 0.5 * m * speed[f] ** 2)
    return t[launch], peak, None


hazardous_at = []
for i, fid in enumerate(frag["id"][:]):
    assert frag["anchored"][i] == anchored[last[fid]]
    assert frag["stayed"][i] == stayed[fid], fid
    result = None if anchored[last[fid]] else flight(fid)
    assert frag["launched"][i] == (result is not None), fid
    if result is None:
        continue
    launch_t, peak, impact = result
    assert math.isclose(frag["launch_time_s"][i], launch_t), fid
    assert math.isclose(frag["peak_kinetic_energy_J"][i], peak, rel_tol=1e-9), (fid, frag["peak_kinetic_energy_J"][i], peak)
    assert frag["impacted"][i] == (impact is not None), fid
    if impact is not None:
        assert math.isclose(frag["impact_time_s"][i], impact[0]) and math.isclose(frag["impact_kinetic_energy_J"][i], impact[1], rel_tol=1e-9)
        if impact[1] >= d.attrs["hazardous_energy_J"] and not stayed[fid]:
            hazardous_at.append(impact[2])
assert frag["hazardous"][:].sum() == len(hazardous_at)

debris = np.array([last[f] for f in frag["id"][:] if not stayed[f]])
rest = pos[debris] - origin
throw = np.hypot(rest[:, 0], rest[:, 1])
assert np.isclose(d.attrs["max_throw_distance_m"], throw.max())
order = np.argsort(throw, kind="stable")
assert np.isclose(d.attrs["median_throw_distance_m"], throw[order][math.ceil(0.5 * len(throw)) - 1])
cum = np.cumsum(mass[debris][order])
assert np.isclose(d.attrs["mass_median_throw_distance_m"], throw[order][np.searchsorted(cum, 0.5 * cum[-1] * (1 - 1e-12))])

# rings: ~20 of a 1-2-5 width out to the farthest resting place or hazardous impact
hz = np.array(hazardous_at).reshape(-1, 3) - origin
hz_r = np.hypot(hz[:, 0], hz[:, 1])
far = max(throw.max(), hz_r.max() if len(hz_r) else 0)
decade = 10 ** math.floor(math.log10(far / 20))
width = min(s * decade for s in (1, 2, 5, 10) if s * decade >= far / 20 * (1 - 1e-12))
n = int(far // width) + 1
edges = np.arange(n + 1) * width
assert np.allclose(d["rings/outer_radius_m"][:], edges[1:])
area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
ring = lambda r: np.minimum(n - 1, (r // width).astype(int))
assert (np.bincount(ring(throw), minlength=n) == d["rings/fragments"][:]).all()
haz = np.bincount(ring(hz_r), minlength=n)
assert (haz == d["rings/hazardous"][:]).all()
sectors = d["rings/sector_hazardous"].shape[1]
sector = (np.floor((np.arctan2(hz[:, 1], hz[:, 0]) + np.pi / sectors) % (2 * np.pi) / (2 * np.pi / sectors)).astype(int)) % sectors
worst = np.zeros((n, sectors), int)
np.add.at(worst, (ring(hz_r), sector), 1)
limit = 1 / d.attrs["hazardous_area_m2"]
hfd = max([edges[i + 1] for i in range(n) if haz[i] / area[i] >= limit], default=0)
hfd_sector = max([edges[i + 1] for i in range(n) if worst[i].max() / (area[i] / sectors) >= limit], default=0)
assert np.isclose(d.attrs["hazardous_fragment_distance_m"], hfd), (d.attrs["hazardous_fragment_distance_m"], hfd)
assert np.isclose(d.attrs["worst_sector_hazardous_fragment_distance_m"], hfd_sector)

# Weibull: least squares of ln(-ln((i - 1/2)/N)) on ln m, masses largest first
m = np.sort(mass[debris])[::-1]
y = np.log(-np.log((np.arange(len(m)) + 0.5) / len(m)))
shape, intercept = np.polyfit(np.log(m), y, 1)
assert np.isclose(d.attrs["weibull_shape"], shape) and np.isclose(d.attrs["weibull_scale_kg"], math.exp(-intercept / shape))
assert np.isclose(d.attrs["weibull_r_squared"], np.corrcoef(np.log(m), y)[0, 1] ** 2)
print(f"debris check: {len(debris)} fragments, {len(hazardous_at)} hazardous, HFD {hfd} m, weibull {shape:.3f}: ok")
