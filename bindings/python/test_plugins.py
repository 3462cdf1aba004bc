"""The Blender add-on's and the MeshLab module's logic without Blender or pymeshlab: label
handling, array conversion, world transforms, and a whole fuse of a demo jaw (ctest's
demo_jaws fixture, jaw_7: seed 8, partial lower arch) through each plugin's code path, checked
in pure Python (closed, consistently oriented teeth; labels; IOS crown vertices kept). When
Blender's `bpy` module or pymeshlab is importable (not in CI), the real add-on operator and
the real pymeshlab path run too."""

import importlib.util
import math
import os
import unittest

import _testsupport as ts
import toothfuse
import toothfuse_meshlab
from toothfuse_blender import convert


def load_jaw7():
    d = ts.jaw_dir(7)
    return ts.read_ply(os.path.join(d, "ios.ply")), ts.read_ply(os.path.join(d, "cbct.ply"))


def split_teeth(xyz, tris, labels):
    """{fdi: (flat xyz, flat tris)} of a mesh of disjoint labeled teeth, re-indexed."""
    out = {}
    for fdi, t in ts.split_by_label(tris, labels).items():
        used = sorted(set(t))
        new = {v: i for i, v in enumerate(used)}
        out[fdi] = ([c for v in used for c in xyz[3 * v:3 * v + 3]], [new[v] for v in t])
    return out


def check_jaw(test, jaw, expected):
    """Fused teeth = expected less skipped; each closed, manifold, oriented, one piece."""
    skipped = [f for f, _ in jaw.skipped]
    test.assertEqual(jaw.teeth, [f for f in expected if f not in skipped])
    test.assertGreaterEqual(len(jaw.teeth), 2)
    per_tooth = ts.split_by_label(list(jaw.triangles), list(jaw.labels))
    test.assertEqual(sorted(per_tooth), jaw.teeth)
    for fdi, t in per_tooth.items():
        e = ts.edge_report(t)
        test.assertEqual((e["boundary"], e["non_manifold"], e["misoriented"]), (0, 0, 0), fdi)
        test.assertEqual(ts.components(t), 1, fdi)
        test.assertGreater(ts.signed_volume(list(jaw.positions), t), 50.0, fdi)
    return per_tooth


class BlenderLogicTest(unittest.TestCase):
    def test_fdi_from_name(self):
        self.assertEqual(convert.fdi_from_name("tooth_36"), 36)
        self.assertEqual(convert.fdi_from_name("CBCT 11.001"), 11)
        self.assertEqual(convert.fdi_from_name("55"), 55)  # primary
        self.assertIsNone(convert.fdi_from_name("Mesh.019"))
        self.assertIsNone(convert.fdi_from_name("tooth 19"))  # not FDI
        self.assertEqual(convert.fdi_from_name("scan 2024 tooth 21"), 21)

    def test_to_world(self):
        # 90 degrees about z, then (10, 20, 30); 1 Blender unit = 2 mm.
        m = [[0, -1, 0, 10], [1, 0, 0, 20], [0, 0, 1, 30], [0, 0, 0, 1]]
        self.assertEqual(convert.to_world([1, 2, 3, -1, 0, 0], m, 2.0),
                         [16, 42, 66, 20, 38, 60])

    def test_object_part_labels(self):
        ident = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
        co = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0]
        tv, tp = [0, 1, 2, 0, 2, 3], [0, 0]  # one quad -> two loop triangles
        p = convert.object_part("q", co, tv, tp, ident, attribute="label", domain="FACE",
                                values=[36])
        self.assertEqual((p.labels, p.per_face), ([36, 36], True))
        p = convert.object_part("q", co, tv, tp, ident, attribute="label", domain="POINT",
                                values=[0, 36.0, 36, 0])
        self.assertEqual((p.labels, p.per_face), ([0, 36, 36, 0], False))
        with self.assertRaisesRegex(ValueError, "36.5 at 1 is not an integer"):
            convert.object_part("q", co, tv, tp, ident, attribute="label", domain="POINT",
                                values=[0, 36.5, 36, 0])
        with self.assertRaisesRegex(ValueError, "on CORNER"):
            convert.object_part("q", co, tv, tp, ident, attribute="label", domain="CORNER",
                                values=[1] * 6)
        p = convert.object_part("tooth_47", co, tv, tp, ident, attribute="label")
        self.assertEqual((p.labels, p.fdi), (None, 47))
        p = convert.object_part("tooth_47", co, tv, tp, ident, attribute="label", fdi=46)
        self.assertEqual(p.fdi, 46)  # the "fdi" property wins over the name
        with self.assertRaisesRegex(ValueError, "Cube: no \"label\" attribute"):
            convert.object_part("Cube", co, tv, tp, ident, attribute="label")

    def test_fuse_through_the_addon_logic(self):
        (ixyz, itri, ip), (cxyz, ctri, cp) = load_jaw7()
        # IOS object: the jaw with a rigid matrix_world (30 degrees about z, shifted), labels
        # on points; CBCT: one object per tooth named tooth_<fdi>, no attribute.
        c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
        m = [[c, -s, 0, 5.0], [s, c, 0, -3.0], [0, 0, 1, 2.0], [0, 0, 0, 1]]
        ios = convert.object_part("IOS scan", ixyz, itri, list(range(len(itri) // 3)), m,
                                  attribute="label", domain="POINT", values=ip["label"])
        ident = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
        cbct = [convert.object_part(f"tooth_{fdi}", x, t, [], ident, attribute="label")
                for fdi, (x, t) in split_teeth(cxyz, ctri, cp["label"]).items()]
        jaw = convert.fuse_parts(ios, cbct, frame="cbct")
        both = sorted((set(ip["label"]) & set(cp["label"])) - {0})
        per_tooth = check_jaw(self, jaw, both)
        # CBCT frame = the CBCT objects' world space: root points are CBCT input points.
        cb = {}
        for i, l in enumerate(cp["label"]):
            cb.setdefault(l, set()).add(tuple(cxyz[3 * i:3 * i + 3]))
        p = list(jaw.positions)
        for fdi, t in per_tooth.items():
            roots = {tuple(p[3 * v:3 * v + 3]) for v in set(t)
                     if jaw.sources[v] == toothfuse.SOURCE_CBCT}
            self.assertTrue(roots and roots <= cb[fdi], fdi)
        verts, faces, labels, sources = convert.mesh_data(jaw, 2.0)
        self.assertEqual(len(verts), len(jaw.labels))
        self.assertEqual(len(faces), len(jaw.triangles) // 3)
        self.assertEqual(verts[1], (p[3] / 2, p[4] / 2, p[5] / 2))
        self.assertEqual((labels, sources), (list(jaw.labels), list(jaw.sources)))
        with self.assertRaisesRegex(ValueError, "select the CBCT"):
            convert.fuse_parts(ios, [])


class FakeMesh:
    """The pymeshlab.Mesh accessors the module uses, over plain lists."""

    def __init__(self, xyz, tris, vattr=None, fattr=None, quality=None):
        self.v = [xyz[i:i + 3] for i in range(0, len(xyz), 3)]
        self.f = [tris[i:i + 3] for i in range(0, len(tris), 3)]
        self.vattr, self.fattr, self.quality = vattr or {}, fattr or {}, quality

    def vertex_matrix(self):
        return self.v

    def face_matrix(self):
        return self.f

    def vertex_custom_scalar_attribute_array(self, name):
        return [float(x) for x in self.vattr[name]]  # KeyError when absent, as pymeshlab raises

    def face_custom_scalar_attribute_array(self, name):
        return [float(x) for x in self.fattr[name]]

    def vertex_scalar_array(self):
        if self.quality is None:
            raise RuntimeError("no vertex quality")
        return self.quality


class MeshLabLogicTest(unittest.TestCase):
    def test_labels(self):
        m = FakeMesh([0] * 9, [0, 1, 2], vattr={"label": [11, 11, 0]}, fattr={"fdi": [21]},
                     quality=[31.0, 31.0, 31.0])
        self.assertEqual(toothfuse_meshlab.mesh_labels(m), ([11, 11, 0], False))
        self.assertEqual(toothfuse_meshlab.mesh_labels(m, "fdi"), ([21], True))
        self.assertEqual(toothfuse_meshlab.mesh_labels(m, "quality"), ([31, 31, 31], False))
        with self.assertRaisesRegex(ValueError, 'no per-vertex or per-face scalar attribute "x"'):
            toothfuse_meshlab.mesh_labels(m, "x")
        bad = FakeMesh([0] * 9, [0, 1, 2], vattr={"label": [11, 11.25, 0]})
        with self.assertRaisesRegex(ValueError, "11.25 at 1 is not an integer"):
            toothfuse_meshlab.mesh_labels(bad)
        with self.assertRaisesRegex(ValueError, "19 is not an FDI"):
            toothfuse_meshlab.mesh_part(m, fdi=19)
        # Explicit labels (pymeshlab's PLY reader drops custom properties) win over attributes.
        self.assertEqual(toothfuse_meshlab.mesh_part(m, labels=([0, 36.0, 36], False))[2:],
                         ([0, 36, 36], False))
        with self.assertRaisesRegex(ValueError, "1 CBCT label sets for 2 CBCT meshes"):
            toothfuse_meshlab.fuse_meshes(m, [m, m], cbct_labels=[([11], True)])

    def test_ply_labels(self):
        (_, _, ip), _ = load_jaw7()
        path = os.path.join(ts.jaw_dir(7), "ios.ply")  # binary little-endian
        self.assertEqual(toothfuse_meshlab.ply_labels(path), (ip["label"], False))
        ascii_ply = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"tf_labels_{os.getpid()}.ply")
        with open(ascii_ply, "w") as f:
            f.write("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 2\n"
                    "property list uchar int vertex_indices\nproperty int label\n"
                    "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 36\n3 0 2 3 0\n")
        try:
            self.assertEqual(toothfuse_meshlab.ply_labels(ascii_ply), ([36, 0], True))
            with self.assertRaisesRegex(ValueError, 'no vertex or face property "fdi"'):
                toothfuse_meshlab.ply_labels(ascii_ply, "fdi")
        finally:
            os.remove(ascii_ply)

    def test_merge_meshes(self):
        xyz, tris, labels = toothfuse.merge_meshes([
            ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], [36, 36, 36], False),
            ([0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1], [0, 1, 2, 1, 3, 2], [37, 38], True),
            ([0, 0, 2, 1, 0, 2, 0, 1, 2], [0, 1, 2], 46, False)])
        self.assertEqual(len(xyz), 30)
        self.assertEqual(tris, [0, 1, 2, 3, 4, 5, 4, 6, 5, 7, 8, 9])
        self.assertEqual(labels, [36, 37, 38, 46])
        with self.assertRaisesRegex(ValueError, "mesh 0: face 0 spans labels 36, 36, 37"):
            toothfuse.merge_meshes([([0] * 9, [0, 1, 2], [36, 36, 37], False)])
        with self.assertRaisesRegex(ValueError, "outside 0..2"):
            toothfuse.merge_meshes([([0] * 9, [0, 1, 3], 36, False)])

    def test_fuse_through_the_meshlab_logic(self):
        (ixyz, itri, ip), (cxyz, ctri, cp) = load_jaw7()
        # IOS with per-face labels (a face is tooth L when its three vertices are), CBCT as
        # one mesh per tooth in a dict {fdi: mesh}; IOS frame.
        lab = ip["label"]
        flab = []
        for t in range(0, len(itri), 3):
            a, b, c = (lab[itri[t + k]] for k in range(3))
            flab.append(a if a == b == c else 0)
        ios = FakeMesh(ixyz, itri, fattr={"label": flab})
        cbct = {fdi: FakeMesh(x, t) for fdi, (x, t) in split_teeth(cxyz, ctri,
                                                                   cp["label"]).items()}
        mesh, jaw = toothfuse_meshlab.fuse_meshes(ios, cbct, frame="ios", as_mesh=False)
        self.assertIsNone(mesh)
        both = sorted((set(lab) & set(cp["label"])) - {0})
        per_tooth = check_jaw(self, jaw, both)
        crowns = ts.crown_points(ixyz, itri, lab)
        p = list(jaw.positions)
        for fdi, t in per_tooth.items():
            kept = {tuple(p[3 * v:3 * v + 3]) for v in set(t)
                    if jaw.sources[v] == toothfuse.SOURCE_IOS}
            self.assertEqual(kept, crowns[fdi], fdi)  # every crown vertex, bit for bit


def _have(module):
    return importlib.util.find_spec(module) is not None


def _split_cbct():
    (ixyz, itri, ip), (cxyz, ctri, cp) = load_jaw7()
    return (ixyz, itri, ip["label"]), split_teeth(cxyz, ctri, cp["label"]), cp["label"]


@unittest.skipUnless(_have("bpy"), "Blender's bpy module is not installed")
class BlenderAddonTest(unittest.TestCase):
    def test_operator(self):
        import bpy
        import toothfuse_blender

        (ixyz, itri, ilab), teeth, clab = _split_cbct()
        toothfuse_blender.register()
        try:
            for o in list(bpy.data.objects):
                bpy.data.objects.remove(o)

            def make(name, xyz, tris, labels=None):
                me = bpy.data.meshes.new(name)
                me.from_pydata([tuple(xyz[i:i + 3]) for i in range(0, len(xyz), 3)], [],
                               [tuple(tris[i:i + 3]) for i in range(0, len(tris), 3)])
                if labels is not None:
                    me.attributes.new("label", "INT", "POINT").data.foreach_set("value",
                                                                                labels)
                ob = bpy.data.objects.new(name, me)
                bpy.context.collection.objects.link(ob)
                ob.select_set(True)
                return ob

            for fdi, (x, t) in teeth.items():
                make(f"tooth_{fdi}", x, t)
            ios = make("IOS", ixyz, itri, ilab)
            ios.location, ios.rotation_euler = (5.0, -3.0, 2.0), (0.0, 0.0, 0.5)
            bpy.context.view_layer.objects.active = ios
            bpy.context.view_layer.update()
            self.assertEqual(bpy.ops.object.toothfuse_fuse(frame="cbct"), {"FINISHED"})
            me = bpy.data.objects["toothfuse_fused"].data
            lab = [0] * len(me.vertices)
            me.attributes["label"].data.foreach_get("value", lab)
            tris = [v for p in me.polygons for v in p.vertices]
            e = ts.edge_report(tris)
            self.assertEqual((e["boundary"], e["non_manifold"], e["misoriented"]), (0, 0, 0))
            self.assertEqual(ts.components(tris), len(set(lab)))
            self.assertTrue(set(lab) <= (set(ilab) & set(clab)) - {0})
            self.assertGreaterEqual(len(set(lab)), 2)
        finally:
            toothfuse_blender.unregister()


@unittest.skipUnless(_have("pymeshlab"), "pymeshlab is not installed")
class PyMeshLabTest(unittest.TestCase):
    def test_fuse_meshset(self):
        import pymeshlab

        d = ts.jaw_dir(7)
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(os.path.join(d, "ios.ply"))
        ms.load_new_mesh(os.path.join(d, "cbct.ply"))
        fid = toothfuse_meshlab.fuse_meshset(
            ms, 0, 1, frame="ios",
            ios_labels=toothfuse_meshlab.ply_labels(os.path.join(d, "ios.ply")),
            cbct_labels=toothfuse_meshlab.ply_labels(os.path.join(d, "cbct.ply")))
        ms.set_current_mesh(fid)
        topo = ms.get_topological_measures()
        self.assertEqual((topo["boundary_edges"], topo["non_two_manifold_edges"]), (0, 0))
        labels = set(ms.mesh(fid).vertex_custom_scalar_attribute_array("label").tolist())
        self.assertEqual(topo["connected_components_number"], len(labels))
        self.assertGreaterEqual(len(labels), 2)


if __name__ == "__main__":
    unittest.main()
