"""toothfuse for Blender: Object > toothfuse: Fuse IOS + CBCT.

Select the CBCT tooth objects, then the IOS jaw object last (active). The IOS object needs an
integer attribute (default "label", on points or faces) holding FDI numbers, 0 = gingiva; each
CBCT object either has the same attribute or is one tooth named by its "fdi" custom property or
its name ("tooth_36"). The result is a new object "toothfuse_fused" (in world space) with
integer point attributes "label" (FDI) and "source" (0 IOS crown, 1 band, 2 CBCT root).

Install: `<blender>/<version>/python/bin/python3 -m pip install ./bindings/python` (the toothfuse
package ships libtoothfuse.so), then copy this folder into Blender's add-ons folder. All logic
lives in convert.py; this file only talks to bpy.
"""

bl_info = {
    "name": "toothfuse",
    "description": "Fuse intraoral-scan crowns with CBCT roots (one watertight mesh per tooth)",
    "version": (0, 1, 0),
    "blender": (3, 0, 0),
    "location": "View3D > Object > toothfuse: Fuse IOS + CBCT",
    "category": "Mesh",
}

try:
    import bpy
except ImportError:  # outside Blender (tests import convert.py only)
    bpy = None


def _read(obj, depsgraph, attribute, scale):
    from . import convert

    ev = obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    try:
        me.calc_loop_triangles()
        co = [0.0] * (3 * len(me.vertices))
        me.vertices.foreach_get("co", co)
        tv = [0] * (3 * len(me.loop_triangles))
        me.loop_triangles.foreach_get("vertices", tv)
        tp = [0] * len(me.loop_triangles)
        me.loop_triangles.foreach_get("polygon_index", tp)
        attr = me.attributes.get(attribute)
        domain = values = None
        if attr is not None:
            domain = attr.domain
            values = [0] * len(attr.data)
            attr.data.foreach_get("value", values)
        fdi = obj.get("fdi")
        return convert.object_part(obj.name, co, tv, tp, [list(r) for r in obj.matrix_world],
                                   attribute=attribute, domain=domain, values=values,
                                   fdi=int(fdi) if fdi is not None else None, scale=scale)
    finally:
        ev.to_mesh_clear()


if bpy is not None:

    class TOOTHFUSE_OT_fuse(bpy.types.Operator):
        """Fuse the active IOS jaw with the selected CBCT teeth into one watertight mesh per
        tooth (toothfuse)"""

        bl_idname = "object.toothfuse_fuse"
        bl_label = "toothfuse: Fuse IOS + CBCT"
        bl_options = {"REGISTER", "UNDO"}

        label_attribute: bpy.props.StringProperty(name="Label attribute", default="label")
        preset: bpy.props.EnumProperty(
            name="Preset", items=[("default", "Default", "measured better"),
                                  ("paper", "Paper", "the paper's method")])
        frame: bpy.props.EnumProperty(
            name="Frame", items=[("cbct", "CBCT", "keep the CBCT objects' placement"),
                                 ("ios", "IOS", "keep the IOS object's placement")])
        ios_repair: bpy.props.BoolProperty(name="Repair IOS crowns", default=False)
        mm_per_unit: bpy.props.FloatProperty(name="mm per Blender unit", default=1.0, min=1e-6)

        @classmethod
        def poll(cls, context):
            ob = context.active_object
            return ob is not None and ob.type == "MESH" and len(context.selected_objects) > 1

        def execute(self, context):
            from . import convert

            dg = context.evaluated_depsgraph_get()
            ios_obj = context.active_object
            try:
                ios = _read(ios_obj, dg, self.label_attribute, self.mm_per_unit)
                cbct = [_read(o, dg, self.label_attribute, self.mm_per_unit)
                        for o in context.selected_objects
                        if o is not ios_obj and o.type == "MESH"]
                jaw = convert.fuse_parts(ios, cbct, preset=self.preset, frame=self.frame,
                                         ios_repair=self.ios_repair)
            except (ValueError, convert.toothfuse.ToothfuseError, OSError) as e:
                self.report({"ERROR"}, str(e))
                return {"CANCELLED"}
            verts, faces, labels, sources = convert.mesh_data(jaw, self.mm_per_unit)
            me = bpy.data.meshes.new("toothfuse_fused")
            me.from_pydata(verts, [], faces)
            me.update()
            for name, values in (("label", labels), ("source", sources)):
                me.attributes.new(name, "INT", "POINT").data.foreach_set("value", values)
            ob = bpy.data.objects.new("toothfuse_fused", me)
            context.collection.objects.link(ob)
            for fdi, reason in jaw.skipped:
                self.report({"WARNING"}, f"tooth {fdi} not fused: {reason}")
            self.report({"INFO"}, f"fused teeth {jaw.teeth}")
            return {"FINISHED"}

    def _menu(self, context):
        self.layout.operator(TOOTHFUSE_OT_fuse.bl_idname)


def register():
    """Registers the operator and its Object menu entry (Blender calls this)."""
    bpy.utils.register_class(TOOTHFUSE_OT_fuse)
    bpy.types.VIEW3D_MT_object.append(_menu)


def unregister():
    """Removes the operator and its menu entry."""
    bpy.types.VIEW3D_MT_object.remove(_menu)
    bpy.utils.unregister_class(TOOTHFUSE_OT_fuse)
