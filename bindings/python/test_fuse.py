"""Registration and one-call fusion through the ctypes bindings on a synthetic jaw of ctest's
demo_jaws fixture (jaw_2: seed 3, partial upper arch), checked in pure Python: every fused tooth
closed, manifold by edge counts, consistently oriented, one component, positive volume; labels
are the teeth in both scans less the skipped ones; every IOS crown vertex is in the output
(source IOS) bit for bit in the IOS frame. Run by ctest (TOOTHFUSE_LIBRARY, TOOTHFUSE_JAWS_DIR
set); plain python3, numpy optional."""

import json
import math
import os
import unittest

import _testsupport as ts
import toothfuse


def load(k):
    d = ts.jaw_dir(k)
    ios = ts.read_ply(os.path.join(d, "ios.ply"))
    cbct = ts.read_ply(os.path.join(d, "cbct.ply"))
    with open(os.path.join(d, "truth", "truth.json")) as f:
        truth = json.load(f)
    return ios, cbct, truth


class FuseTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.ios, cls.cbct, cls.truth = load(2)
        ios_l = cls.ios[2]["label"]
        cbct_l = cls.cbct[2]["label"]
        cls.both = sorted((set(ios_l) & set(cbct_l)) - {0})

    def test_one_call_fuse_ios_frame(self):
        (ixyz, itri, ip), (cxyz, ctri, cp) = self.ios, self.cbct
        jaw = toothfuse.fuse(ixyz, itri, ip["label"], cxyz, ctri, cp["label"], frame="ios",
                             as_numpy=False)
        self.assertGreaterEqual(len(self.both), 3)
        skipped = [f for f, _ in jaw.skipped]
        for f, reason in jaw.skipped:
            print(f"tooth {f} skipped: {reason}")
            self.assertTrue(reason)
        self.assertEqual(jaw.teeth, [f for f in self.both if f not in skipped])
        self.assertGreaterEqual(len(jaw.teeth), 3)
        self.assertEqual(jaw.report["frame"], "ios")
        xyz, tris = list(jaw.positions), list(jaw.triangles)
        n = len(xyz) // 3
        self.assertEqual(len(jaw.labels), n)
        self.assertEqual(len(jaw.sources), n)
        self.assertEqual(set(jaw.sources), {toothfuse.SOURCE_IOS, toothfuse.SOURCE_BAND,
                                            toothfuse.SOURCE_CBCT})
        per_tooth = ts.split_by_label(tris, jaw.labels)
        self.assertEqual(sorted(per_tooth), jaw.teeth)
        crowns = ts.crown_points(ixyz, itri, ip["label"])
        for fdi, t in per_tooth.items():
            with self.subTest(tooth=fdi):
                e = ts.edge_report(t)
                self.assertEqual((e["boundary"], e["non_manifold"], e["misoriented"]), (0, 0, 0))
                # Euler characteristic of a closed sphere-like surface: V - E + F = 2.
                verts = set(t)
                self.assertEqual(len(verts) - e["edges"] + len(t) // 3, 2)
                self.assertEqual(ts.components(t), 1)
                vol = ts.signed_volume(xyz, t)
                self.assertGreater(vol, 50.0)
                q = jaw.quality[fdi]
                self.assertTrue(q["closed"] and q["manifold"])
                self.assertEqual(q["boundary_edges"], 0)
                self.assertTrue(math.isclose(q["volume"], vol, rel_tol=1e-9))
                crown = [tuple(xyz[3 * v:3 * v + 3]) for v in sorted(verts)
                         if jaw.sources[v] == toothfuse.SOURCE_IOS]
                self.assertEqual(len(set(crown)), len(crown))
                # Every IOS crown vertex is kept bitwise, except the ones the library reports
                # trimmed from the folded margin fringe (none or a few, within 0.3 mm).
                self.assertTrue(set(crown) <= crowns[fdi])
                self.assertEqual(len(crowns[fdi]) - len(crown), q["ios_vertices_trimmed"])
                self.assertEqual(q["ios_vertices_dropped"], 0)
                self.assertLessEqual(q["ios_trim_reach_mm"], 0.3)
                self.assertEqual(q["crown_vertices"], len(crown))
                # No crossing added by the fusion; the phantom's crowns do not cross themselves.
                self.assertEqual(q["band_crossings_left"], 0)
                self.assertEqual(q["ios_self_intersections"], 0)
                # IOS frame: the IOS -> output transform is the identity.
                self.assertEqual(jaw.transforms[fdi]["ios_to_output"],
                                 [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0])

    def test_register_against_truth(self):
        (ixyz, itri, ip), (cxyz, ctri, cp) = self.ios, self.cbct
        true = {t["fdi"]: t["cbct_to_ios"] for t in self.truth["teeth"]}
        with toothfuse.Session() as s:
            s.add_jaw(toothfuse.IOS, ixyz, itri, ip["label"])
            s.add_jaw(toothfuse.CBCT, cxyz, ctri, cp["label"])
            self.assertEqual(s.register(), self.both)
            self.assertEqual(s.registered_teeth(), self.both)
            self.assertEqual(s.report()["frame"], "cbct")
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.fused_teeth()  # registered, not fused
            self.assertEqual(e.exception.status, 10)  # WRONG_STATE
            for fdi in self.both:
                m = s.transform(fdi, "cbct_to_ios")
                rot = [m[0:3], m[4:7], m[8:11]]
                for i in range(3):
                    for j in range(3):
                        dot = sum(rot[i][k] * rot[j][k] for k in range(3))
                        self.assertAlmostEqual(dot, 1.0 if i == j else 0.0, places=9)
                self.assertEqual(m[12:], [0.0, 0.0, 0.0, 1.0])
                # TRE: RMS over the CBCT tooth's vertices of estimated vs true mapping.
                idx = [i for i, l in enumerate(cp["label"]) if l == fdi]
                sq = 0.0
                for i in idx:
                    a, b = ts.apply(m, cxyz, i), ts.apply(true[fdi], cxyz, i)
                    sq += sum((a[k] - b[k]) ** 2 for k in range(3))
                tre = math.sqrt(sq / len(idx))
                rep = s.tooth_report(fdi)
                print(f"tooth {fdi}: TRE {tre:.3f} mm, SD {rep['sd_mm']:.3f} mm")
                self.assertTrue(tre <= 0.5 or rep["warnings"], f"tooth {fdi}: TRE {tre:.3f} mm")
                self.assertGreater(rep["inlier_fraction"], 0.5)

    def test_stages_register_cut_stitch(self):
        (ixyz, itri, ip), (cxyz, ctri, cp) = self.ios, self.cbct
        with toothfuse.Session() as s:
            s.add_jaw(toothfuse.IOS, ixyz, itri, ip["label"])
            s.add_jaw(toothfuse.CBCT, cxyz, ctri, cp["label"])
            for stage in (s.cut, s.stitch, s.fuse_registered):
                with self.assertRaises(toothfuse.ToothfuseError) as e:
                    stage()  # not registered
                self.assertEqual(e.exception.status, 10)  # WRONG_STATE
            s.register()
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.stitch()  # registered, not cut
            self.assertEqual(e.exception.status, 10)
            self.assertIn("no cut", str(e.exception))
            cut = s.cut()
            self.assertGreaterEqual(len(cut), 3)
            self.assertEqual(s.cut_teeth(), cut)
            roots = {f: s.cut_root(f) for f in cut}
            fused = s.stitch()
            self.assertEqual(fused, cut)
            staged = {f: s.fused_mesh(f) for f in fused}
            # fuse_registered (cut + stitch in one call) gives the same meshes, bit for bit.
            self.assertEqual(s.fuse_registered(), fused)
            for f in fused:
                self.assertEqual(s.fused_mesh(f), staged[f])
            for f, (pos, idx, loop) in roots.items():
                with self.subTest(tooth=f):
                    tris = list(idx)
                    e = ts.edge_report(tris)
                    # An open manifold root whose boundary is exactly the cut loop, in order.
                    self.assertEqual((e["non_manifold"], e["misoriented"]), (0, 0))
                    self.assertEqual(e["boundary"], len(loop))
                    self.assertEqual(len(set(loop)), len(loop))
                    directed = {(t[k], t[(k + 1) % 3])
                                for t in zip(tris[0::3], tris[1::3], tris[2::3])
                                for k in range(3)}
                    for a, b in zip(loop, list(loop[1:]) + [loop[0]]):
                        self.assertIn((a, b), directed)
                        self.assertNotIn((b, a), directed)
                    # The fused tooth's CBCT vertices are the cut root's, bit for bit.
                    fpos, _, src, _ = staged[f]
                    cbct = [fpos[3 * v + k] for v in range(len(src))
                            if src[v] == toothfuse.SOURCE_CBCT for k in range(3)]
                    self.assertEqual(cbct, list(pos))
            s.remove_tooth(toothfuse.IOS, fused[0])
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.cut_root(fused[1])  # the cut was dropped with the teeth change
            self.assertEqual(e.exception.status, 10)

    def test_errors(self):
        (ixyz, itri, ip), (cxyz, ctri, cp) = self.ios, self.cbct
        one = [l if l == self.both[0] else 0 for l in cp["label"]]
        with self.assertRaises(toothfuse.ToothfuseError) as e:
            toothfuse.fuse(ixyz, itri, ip["label"], cxyz, ctri, one)
        self.assertEqual(e.exception.status, 7)  # MISSING_DATA: one tooth in both
        self.assertIn("missing data", str(e.exception))
        with self.assertRaises(ValueError):
            toothfuse.fuse(ixyz, itri, ip["label"], cxyz, ctri, cp["label"], preset="best")
        with self.assertRaises(ValueError):
            with toothfuse.Session() as s:
                s.transform(11, "ios_to_cbct")

    def test_numpy_inputs_and_outputs(self):
        np = toothfuse._core._numpy()
        if np is None:
            self.skipTest("numpy is not installed (optional)")
        (ixyz, itri, ip), (cxyz, ctri, cp) = self.ios, self.cbct
        with toothfuse.Session() as s:  # registration only: fast
            s.add_jaw(toothfuse.IOS, np.array(ixyz, dtype=np.float64).reshape(-1, 3),
                      np.array(itri, dtype=np.int64).reshape(-1, 3), np.array(ip["label"]))
            s.add_jaw(toothfuse.CBCT, np.array(cxyz).reshape(-1, 3), np.array(ctri),
                      np.array(cp["label"], dtype=np.int32))
            self.assertEqual(s.teeth(toothfuse.CBCT), self.both)
            pos, _ = s.mesh(toothfuse.IOS, self.both[0])
            crowns = ts.crown_points(ixyz, itri, ip["label"])
            got = {tuple(pos[i:i + 3]) for i in range(0, len(pos), 3)}
            self.assertEqual(got, crowns[self.both[0]])
        # fuse() returns numpy arrays for numpy input (jaw_7: a small partial arch).
        (ixyz, itri, ip), (cxyz, ctri, cp), _ = load(7)
        jaw = toothfuse.fuse(np.array(ixyz).reshape(-1, 3), np.array(itri).reshape(-1, 3),
                             np.array(ip["label"]), np.array(cxyz, dtype=np.float32),
                             np.array(ctri), np.array(cp["label"]))
        n = len(jaw.labels)
        self.assertEqual((jaw.positions.shape, jaw.positions.dtype), ((n, 3), np.float64))
        self.assertEqual((jaw.triangles.shape[1], jaw.triangles.dtype), (3, np.uint32))
        self.assertEqual((jaw.labels.dtype, jaw.sources.dtype), (np.int32, np.uint8))
        self.assertEqual(sorted(set(jaw.labels.tolist())), jaw.teeth)
        e = ts.edge_report(jaw.triangles.reshape(-1).tolist())
        self.assertEqual((e["boundary"], e["non_manifold"], e["misoriented"]), (0, 0, 0))


if __name__ == "__main__":
    unittest.main()
