"""What the simulator injected into a stepped workpiece, read from its truth.json alone (not
from the evaluation's code): shared by the separation and campaign tests."""


def along_normal(feature, key):
    """A cut's vector (deflection_um, ...) along the as-cut wall's outward normal."""
    n, d = feature["as_cut"]["normal"], feature["machine"][key]
    return sum(n[i] * d[i] for i in range(3))


class SwTruth:
    def __init__(self, truth, manifest):
        self.feats = {f["id"]: f for f in truth["features"]}
        feature_of = {p["position"]: p["feature"] for p in manifest["points"]}
        self.events = {}
        for e in truth["events"]:
            self.events.setdefault(feature_of[e["position"]], []).append(e)
        sw = manifest["stepped_workpiece"]
        self.sizes = sw["sizes_mm"]
        self.tool_d = sw["tool_diameter_mm"]

    def mean_axis(self, feature, a):
        v = [e["axes_um"][a] for e in self.events[feature]]
        return sum(v) / len(v)

    def scale(self, record, a):
        return (record.get("scale_um_per_mm") or [0, 0, 0])[a]

    def deflection(self, k, a):
        """Two-wall sum of the tool's deflection away from the material (um)."""
        P, N = ("XP", "XN") if a == 0 else ("YP", "YN")
        return along_normal(self.feats[f"S{k}_{P}"], "deflection_um") + along_normal(self.feats[f"S{k}_{N}"], "deflection_um")

    def lost_motion(self, k, a):
        """Two-wall sum of the drives' lost motion held when step k's walls were cut (um, outward):
        the simulator's control error (structure.lost_motion_*), 0 when the truth has none."""
        P, N = ("XP", "XN") if a == 0 else ("YP", "YN")
        return sum(along_normal(self.feats[f"S{k}_{w}"], "lost_motion_um") if "lost_motion_um" in self.feats[f"S{k}_{w}"]["machine"] else 0.0
                   for w in (P, N))

    def thermal(self, k, a):
        """The thermal position error e_pt of step k's width (um): the axis's scale error when the
        two walls were cut minus when the probe touched them (CMM - probe puts that one into
        e_pos), over the tool centre's travel (size + tool d)."""
        P, N = ("XP", "XN") if a == 0 else ("YP", "YN")
        cut = (self.scale(self.feats[f"S{k}_{P}"]["machine"], a) + self.scale(self.feats[f"S{k}_{N}"]["machine"], a)) / 2
        ev = self.events[f"S{k}_{P}"] + self.events[f"S{k}_{N}"]
        probe = sum(self.scale(e, a) for e in ev) / len(ev)
        return (cut - probe) * (self.sizes[k - 1] + self.tool_d)

    def thermal_from_zero(self, k, a):
        """e_pt as the campaign separates it (seed 000 Sec. 3.5): the scale error when step k's walls
        were cut minus at the thermal zero, the top's cut (finishing's first, T = 0), over the tool
        centre's travel. What thermal() holds beyond it, (top - probe) x travel, grows with the
        step as T does: a stage's line takes part of it with e_pt, its intercept the rest."""
        P, N = ("XP", "XN") if a == 0 else ("YP", "YN")
        cut = (self.scale(self.feats[f"S{k}_{P}"]["machine"], a) + self.scale(self.feats[f"S{k}_{N}"]["machine"], a)) / 2
        return (cut - self.scale(self.feats["TOP"]["machine"], a)) * (self.sizes[k - 1] + self.tool_d)
