"""rotate_pair.py IN OUT BEARING PAIR ANGLE_DEG: the run directory IN copied
to OUT with BEARING's PAIR (rel or ped) written turned by ANGLE_DEG, as a
pair of transducers mounted at that angle and written as they read
(scripts/ross_unseen.py add_probe_axes: first channel cos a*y - sin a*z,
second sin a*y + cos a*z; the noise columns turned as independent noise)."""
import csv, json, math, shutil, sys
src, dst, bearing, pair, angle = sys.argv[1:6]
a = math.radians(float(angle))
c, s = math.cos(a), math.sin(a)
shutil.copytree(src, dst)
with open(f"{src}/measurements.csv") as f:
    rows = list(csv.reader(f))
head, body = rows[0], rows[1:]
col = {n: i for i, n in enumerate(head)}
for r in body:
    if r[col["bearing"]] != bearing:
        continue
    for part in ("re", "im"):
        y, z = float(r[col[f"{pair}_y_{part}"]]), float(r[col[f"{pair}_z_{part}"]])
        r[col[f"{pair}_y_{part}"]] = "%.6e" % (c * y - s * z)
        r[col[f"{pair}_z_{part}"]] = "%.6e" % (s * y + c * z)
    if f"{pair}_y_sd" in col:
        vy, vz = float(r[col[f"{pair}_y_sd"]]) ** 2, float(r[col[f"{pair}_z_sd"]]) ** 2
        r[col[f"{pair}_y_sd"]] = "%.3e" % math.sqrt(c * c * vy + s * s * vz)
        r[col[f"{pair}_z_sd"]] = "%.3e" % math.sqrt(s * s * vy + c * c * vz)
with open(f"{dst}/measurements.csv", "w", newline="") as f:
    csv.writer(f, lineterminator="\n").writerows([head] + body)
t = json.load(open(f"{src}/truth.json"))
t.setdefault("effect_details", []).append(
    {"name": "probe_axes" if pair == "rel" else "pickup_axes", "bearing": bearing, "parameters": {"angle_deg": float(angle)}})
json.dump(t, open(f"{dst}/truth.json", "w"), indent=1)
