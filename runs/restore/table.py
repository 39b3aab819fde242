"""Print the old (published) and new cross-check side by side."""
import json, sys
old = json.load(open("/work/main/grip_env/data/standard/crosscheck/crosscheck.json"))["crosscheck"]
new = json.load(open(sys.argv[1]))["crosscheck"]
def f(g, k, pct=False):
    v = g.get(k); iv = g.get(k + "_interval")
    if v is None: return "-"
    s = f"{100*v:.1f} %" if pct else f"{v:.3f}"
    if iv: s += f" [{100*iv[0]:.1f}, {100*iv[1]:.1f}]" if pct else f" [{iv[0]:.2f}, {iv[1]:.2f}]"
    return s
rows = [("trials judged alike", "agreement", True), ("kappa", "kappa", False),
        ("within-object Spearman", "within", False), ("retest PyBullet", "retest_own", False),
        ("retest MuJoCo", "retest_other", False), ("pooled Spearman", "pooled", False),
        ("top-1 PyBullet's first in MuJoCo", "top1_own", True), ("top-1 MuJoCo's first in PyBullet", "top1_other", True),
        ("share: grip", "share_grip", True), ("share: engine", "share_engine", True), ("share: draws", "share_draws", True),
        ("mean robustness PyBullet (g)", "robustness_own", False), ("mean robustness MuJoCo (g)", "robustness_other", False)]
print("| figure | `2026.12-worm` | `2026.12-restore` |\n| --- | --- | --- |")
for name, k, pct in rows:
    print(f"| {name} | {f(old['overall'], k, pct)} | {f(new['overall'], k, pct)} |")
for group in ("families", "by_pieces", "by_grips"):
    for g in new[group]:
        o, n = old[group][g], new[group][g]
        print(f"| {g} ({n['objects']}): within; alike; engine share; PyBullet/MuJoCo g | {o['within']:.2f}; {100*o['agreement']:.1f} %; {100*o['share_engine']:.1f} %; {o['robustness_own']:.1f}/{o['robustness_other']:.1f} | {n['within']:.2f}; {100*n['agreement']:.1f} %; {100*n['share_engine']:.1f} %; {n['robustness_own']:.1f}/{n['robustness_other']:.1f} |")
print(new["summary"] if "summary" in new else "")
print(new.get("cost"))
