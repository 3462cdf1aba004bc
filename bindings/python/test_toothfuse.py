"""Test of the ctypes bindings (run by ctest with TOOTHFUSE_LIBRARY set)."""

import array
import math
import unittest

import toothfuse


def ctypes_sizeof_options():
    import ctypes
    return ctypes.sizeof(toothfuse._core._Options)

CUBE = [0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0, 0, 0, 2, 2, 0, 2, 2, 2, 2, 0, 2, 2]
CUBE = [c + 0.1 for c in CUBE]
TRIS = [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
        1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7]


class BindingsTest(unittest.TestCase):
    def test_versions(self):
        self.assertEqual(toothfuse.abi_version(), toothfuse.ABI_VERSION)
        self.assertRegex(toothfuse.version(), r"^\d+\.\d+\.\d+$")

    def test_add_list_read_back(self):
        with toothfuse.Session() as s:
            s.add_tooth(toothfuse.CBCT, 16, CUBE, TRIS)
            s.add_tooth(toothfuse.CBCT, 15, array.array("f", CUBE), TRIS)
            self.assertEqual(s.teeth(toothfuse.CBCT), [15, 16])
            self.assertEqual(s.teeth(toothfuse.IOS), [])
            pos, idx = s.mesh(toothfuse.CBCT, 16)
            self.assertEqual(list(pos), CUBE)  # bit for bit
            self.assertEqual(list(idx), TRIS)
            pos, _ = s.mesh(toothfuse.CBCT, 15)
            self.assertEqual(list(pos), list(array.array("f", CUBE)))  # exact float -> double
            info = s.info(toothfuse.CBCT, 16)
            self.assertTrue(info["closed"] and info["manifold"])
            self.assertTrue(math.isclose(info["signed_volume"], 8.0, rel_tol=1e-12))
            s.remove_tooth(toothfuse.CBCT, 15)
            self.assertEqual(s.teeth(toothfuse.CBCT), [16])

    def test_label_volume(self):
        # A ball of radius 3 mm labelled 36 on a 0.25 mm grid with LPS-style negative x, y steps.
        n, h, r = 32, 0.25, 3.0
        labels = array.array("H", [0]) * (n * n * n)
        for k in range(n):
            for j in range(n):
                for i in range(n):
                    x, y, z = (i - 15.5) * h, (j - 15.5) * h, (k - 15.5) * h
                    if x * x + y * y + z * z < r * r:
                        labels[i + n * (j + n * k)] = 36
        m = [-h, 0, 0, 10 + 15.5 * h, 0, -h, 0, 20 + 15.5 * h, 0, 0, h, 30 - 15.5 * h,
             0, 0, 0, 1]
        with toothfuse.Session() as s:
            self.assertEqual(s.add_label_volume(labels, (n, n, n), voxel_to_world=m), 1)
            self.assertEqual(s.teeth(toothfuse.CBCT), [36])
            info = s.info(toothfuse.CBCT, 36)
            self.assertTrue(info["closed"] and info["manifold"])
            exact = 4.0 / 3.0 * math.pi * r ** 3
            self.assertLess(abs(info["signed_volume"] - exact) / exact, 0.03)
            pos, _ = s.mesh(toothfuse.CBCT, 36)
            for q in range(0, len(pos), 3):
                d = math.dist(pos[q:q + 3], (10, 20, 30))
                self.assertLess(abs(d - r), 0.1)
            # Negative labels (an intensity image) are refused, the session unchanged.
            bad = array.array("h", [-5]) * (n * n * n)
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_label_volume(bad, (n, n, n), spacing=(h, h, h), origin=(0, 0, 0))
            self.assertIn("outside 0-65535", str(e.exception))
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_label_volume(labels, (n, n, n - 1), voxel_to_world=m)
            self.assertIn("does not match dims", str(e.exception))
            self.assertEqual(s.teeth(toothfuse.CBCT), [36])

    def test_jaw_and_errors(self):
        with toothfuse.Session() as s:
            # Per-face labels: the cube's first 6 faces are crown 11 (open), the rest gingiva.
            labels = [11] * 6 + [0] * 6
            self.assertEqual(s.add_jaw(toothfuse.IOS, CUBE, TRIS, labels, per_face=True), [11])
            self.assertEqual(s.info(toothfuse.IOS, 11)["boundary_loops"], 1)
            src = s.source_vertices(toothfuse.IOS, 11)
            pos, _ = s.mesh(toothfuse.IOS, 11)
            for i, j in enumerate(src):
                self.assertEqual(list(pos[3 * i:3 * i + 3]), CUBE[3 * j:3 * j + 3])
            bad = list(CUBE)
            bad[4] = float("nan")
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_tooth(toothfuse.CBCT, 21, bad, TRIS)
            self.assertEqual(e.exception.status, 3)
            self.assertIn("tooth 21: vertex 1 has a non-finite coordinate", str(e.exception))
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_jaw(toothfuse.IOS, CUBE, TRIS, [19] * 12, per_face=True)
            self.assertIn("label 19 (on face 0) is not an FDI tooth number", str(e.exception))
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.mesh(toothfuse.CBCT, 21)
            self.assertIn("no CBCT tooth 21", str(e.exception))
            self.assertEqual(s.teeth(toothfuse.IOS), [11])
            self.assertEqual(s.teeth(toothfuse.CBCT), [])

    def test_units_are_checked_on_entry(self):
        with toothfuse.Session() as s:
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_tooth(toothfuse.CBCT, 21, [c * 0.001 for c in CUBE], TRIS)
            self.assertEqual(e.exception.status, toothfuse.STATUS_UNIT_MISMATCH)
            self.assertIn("CBCT", str(e.exception))
            self.assertIn("metres", str(e.exception))
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_jaw(toothfuse.IOS, [c * 1000 for c in CUBE], TRIS, [11] * 6 + [0] * 6,
                          per_face=True)
            self.assertEqual(e.exception.status, toothfuse.STATUS_UNIT_MISMATCH)
            self.assertIn("micrometres", str(e.exception))
            self.assertEqual(s.teeth(toothfuse.CBCT), [])
            # The override reaches the library: an unknown value would be refused there.
            o = toothfuse._core._options("default", "cbct", accept_questionable=True)
            self.assertEqual(o.accept_questionable, 1)
            self.assertEqual(o.struct_size, ctypes_sizeof_options())

    def test_ios_repair(self):
        with toothfuse.Session() as s:
            # A bow tie: two crown triangles touching at one vertex.
            v = [0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0]
            t = [0, 1, 2, 0, 3, 4]
            with self.assertRaises(toothfuse.ToothfuseError) as e:
                s.add_tooth(toothfuse.IOS, 31, v, t)
            self.assertIn("vertex 0 is non-manifold", str(e.exception))
            # The refusal says how to have the crown repaired on entry.
            self.assertIn("ios_repair=True", str(e.exception))
            s.set_ios_repair(True)
            s.add_tooth(toothfuse.IOS, 31, v, t)
            self.assertTrue(s.info(toothfuse.IOS, 31)["manifold"])
            with self.assertRaises(toothfuse.ToothfuseError):
                s.set_ios_repair(True, 2.0)


if __name__ == "__main__":
    unittest.main()
