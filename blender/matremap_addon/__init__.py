"""matremap for Blender: convert the spec-gloss materials of an imported glTF to a Principled BSDF with converted
textures, and remap a Principled BSDF's values from or to any model matremap knows (docs/blender-addon.md)."""

bl_info = {
    "name": "matremap",
    "author": "matremap authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Material > matremap",
    "description": "Spec-gloss glTF materials to Principled BSDF; remap Principled values to/from other models",
    "doc_url": "https://github.com/matremap/matremap/blob/main/docs/blender-addon.md",
    "category": "Material",
}

import time

import bpy
from bpy.props import EnumProperty, IntProperty, PointerProperty, StringProperty

from . import package
from . import nodes as N

REPORT_TEXT = "matremap report"
SELF_MODEL = "cycles-principled"  # Blender 3.x's Principled BSDF v1 in matremap (src/brdf/cycles_principled.c)
METHODS = (("mlp", "mlp", "the trained network (matremap's default): weighted where exact, learned elsewhere"),
           ("weighted", "weighted", "Eq. 3 per channel, one albedo-weighted metallic"),
           ("mean", "mean", "Eq. 3 per channel, the mean metallic"),
           ("khronos", "khronos", "the glTF project's converter (perceived brightness)"))

_model_items = []  # Blender needs the enum strings kept alive


def prefs(context=None):
    context = context or bpy.context
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def load_package(context=None):
    p = prefs(context)
    return package.load(p.library if p else "")


def model_items(self, context):
    if _model_items:
        return _model_items
    mr = load_package(context)
    if mr is None:
        return [("gltf", "gltf", "matremap is not loaded")]
    for m in mr.models():
        if m["name"] == SELF_MODEL:
            continue
        _model_items.append((m["name"], m["name"], m.get("summary", "")[:200]))
    return _model_items or [("gltf", "gltf", "")]


def write_report(title, lines):
    """The details go to the text block 'matremap report' (newest run first)."""
    text = bpy.data.texts.get(REPORT_TEXT) or bpy.data.texts.new(REPORT_TEXT)
    old = text.as_string()
    text.clear()
    text.write("# %s  (%s)\n%s\n\n%s" % (title, time.strftime("%Y-%m-%d %H:%M:%S"), "\n".join(lines), old))
    return text


def _finish(op, context, title, lines, summary, flags):
    write_report(title, lines + ["flagged: %s" % f for f in flags])
    msg = summary + (("; flagged: " + "; ".join(flags)) if flags else "")
    context.scene.matremap.last_report = msg[:1000]
    op.report({"WARNING"} if flags else {"INFO"}, msg)


class MatremapPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    def _changed(self, context):
        package.reset()
        _model_items.clear()

    library: StringProperty(name="Library", subtype="FILE_PATH", update=_changed,
                            description="libmatremap.so.0 to use (empty: $MATREMAP_LIBRARY, the installed one, "
                                        "else the build tree that made this add-on)")

    def draw(self, context):
        self.layout.prop(self, "library")
        mr = load_package(context)
        self.layout.label(text=package.where() if mr else (package.error() or "not loaded"))


class MatremapSettings(bpy.types.PropertyGroup):
    method: EnumProperty(name="Method", items=METHODS, default="mlp")
    mode: EnumProperty(name="Result", default="NEW", items=(
        ("NEW", "New material", "a new material (name + suffix) takes the object slots; the old one is kept"),
        ("REPLACE", "Replace", "rewrite the material's own node tree")))
    scope: EnumProperty(name="Materials", default="SELECTED", items=(
        ("ACTIVE", "Active", "the active object's active material"),
        ("SELECTED", "Selected objects", "every material of the selected objects"),
        ("ALL", "All", "every material in the file")))
    suffix: StringProperty(name="Suffix", default="_metalrough")
    save_dir: StringProperty(name="Save textures to", subtype="DIR_PATH", default="",
                             description="empty: pack the new textures into the .blend")
    model: EnumProperty(name="Model", items=model_items)
    direction: EnumProperty(name="Direction", default="TO", items=(
        ("TO", "Principled -> model", "the model's values that look like this Principled (stored on the material)"),
        ("FROM", "model -> Principled", "set this Principled from the model's values stored on the material")))
    size: IntProperty(name="Fit size", default=64, min=16, max=512)
    last_report: StringProperty(name="Last", default="")


def _materials(context, scope):
    if scope == "ALL":
        return list(bpy.data.materials)
    if scope == "ACTIVE":
        ob = context.object
        return [ob.active_material] if ob is not None and ob.active_material else []
    seen = []
    for ob in context.selected_objects:
        for slot in ob.material_slots:
            if slot.material is not None and slot.material not in seen:
                seen.append(slot.material)
    return seen


class MATREMAP_OT_convert_specgloss(bpy.types.Operator):
    """Convert spec-gloss materials (as Blender's glTF importer builds them) to a Principled BSDF with
    converted base colour and metallic-roughness textures"""
    bl_idname = "matremap.convert_specgloss"
    bl_label = "Spec-gloss to Principled"
    bl_options = {"REGISTER", "UNDO"}

    method: EnumProperty(name="Method", items=METHODS, default="mlp")
    mode: EnumProperty(name="Result", default="NEW", items=(("NEW", "New material", ""), ("REPLACE", "Replace", "")))
    scope: EnumProperty(name="Materials", default="SELECTED", items=(
        ("ACTIVE", "Active", ""), ("SELECTED", "Selected objects", ""), ("ALL", "All", "")))
    suffix: StringProperty(name="Suffix", default="_metalrough")
    save_dir: StringProperty(name="Save textures to", subtype="DIR_PATH", default="")

    def execute(self, context):
        from . import convert
        mr = load_package(context)
        if mr is None:
            self.report({"ERROR"}, package.error())
            return {"CANCELLED"}
        mats = [m for m in _materials(context, self.scope) if m.use_nodes and N.find_specgloss(m)[0]]
        if not mats:
            self.report({"WARNING"}, "no spec-gloss material (Diffuse + Glossy BSDF from the glTF importer) in %s"
                        % self.scope.lower())
            return {"CANCELLED"}
        save_dir = bpy.path.abspath(self.save_dir) if self.save_dir else ""
        lines, flags, done = [package.where() or ""], [], []
        t0 = time.time()
        for mat in mats:
            lines.append("%s (method %s):" % (mat.name, self.method))
            try:
                target, images, notes = convert.convert_material(mr, mat, self.method, self.mode, self.suffix,
                                                                 save_dir, lines)
            except (convert.Flagged, N.Unsupported) as exc:
                flags.append("%s: %s" % (mat.name, exc))
                continue
            except Exception as exc:  # matremap.Error, ValueError: the library's message
                flags.append("%s: %s" % (mat.name, exc))
                continue
            lines.append("  -> %s: Principled BSDF '%s'%s" % (target.name, "matremap Principled",
                         (", images " + ", ".join(i.name for i in images)) if images else " (constants)"))
            flags.extend(notes)
            done.append(target.name)
        summary = "converted %d of %d spec-gloss material(s) in %.1f s%s" % (
            len(done), len(mats), time.time() - t0, (": " + ", ".join(done)) if done else "")
        _finish(self, context, "Spec-gloss to Principled", lines, summary, flags)
        return {"FINISHED"} if done else {"CANCELLED"}


def _key(model, param):
    return "matremap:%s:%s" % (model, param)


def _model_info(mr, name):
    for m in mr.models():
        if m["name"] == name:
            return m
    raise ValueError("matremap knows no model '%s'" % name)


def _fmt(v):
    if isinstance(v, (tuple, list)):
        return "(%s)" % ", ".join("%.4g" % x for x in v)
    return "%.4g" % v


class MATREMAP_OT_remap_principled(bpy.types.Operator):
    """Remap the active material's Principled BSDF to another model (values stored on the material as custom
    properties 'matremap:MODEL:PARAM') or set it from that model's stored values"""
    bl_idname = "matremap.remap_principled"
    bl_label = "Remap Principled"
    bl_options = {"REGISTER", "UNDO"}

    model: EnumProperty(name="Model", items=model_items)
    direction: EnumProperty(name="Direction", default="TO", items=(
        ("TO", "Principled -> model", ""), ("FROM", "model -> Principled", "")))
    size: IntProperty(name="Fit size", default=64, min=16, max=512)

    def execute(self, context):
        mr = load_package(context)
        if mr is None:
            self.report({"ERROR"}, package.error())
            return {"CANCELLED"}
        ob = context.object
        mat = ob.active_material if ob is not None else None
        node = N.find_principled(mat)
        if node is None:
            self.report({"ERROR"}, "the active material has no Principled BSDF")
            return {"CANCELLED"}
        model = self.model
        flags, lines = [], [package.where() or ""]
        if N.is_v2(node):
            flags.append("Blender 4.x's Principled BSDF (v2) is not matremap's cycles-principled (Blender 3.x's v1): "
                         "the values are carried over by name")
        try:
            info = _model_info(mr, model)
            if self.direction == "TO":
                vals = {}
                for param in N.PRINCIPLED_INPUTS:
                    v, note = N.get_principled_value(node, param)
                    if note:
                        flags.append(note)
                    if v is not None:
                        vals[param] = v
                res = mr.remap(SELF_MODEL, vals, model, size=self.size)
                for name, v in res.values.items():
                    mat[_key(model, name)] = list(v) if isinstance(v, (tuple, list)) else float(v)
                src_txt = ", ".join("%s %s" % (k, _fmt(v)) for k, v in vals.items())
                dst_txt = ", ".join("%s %s" % (k, _fmt(v)) for k, v in res.values.items())
                lines += ["%s: Principled (%s) -> %s (%s)" % (mat.name, src_txt, model, dst_txt)]
                what = "Principled -> %s" % model
            else:
                params = {}
                for p in info["params"]:
                    key = _key(model, p["name"])
                    if key in mat:
                        v = mat[key]
                        params[p["name"]] = tuple(float(x) for x in v) if p["channels"] == 3 else float(v)
                    else:
                        d = p["default"]
                        params[p["name"]] = (tuple(d) if isinstance(d, (list, tuple)) else (d,) * 3) \
                            if p["channels"] == 3 else float(d[0] if isinstance(d, (list, tuple)) else d)
                        v = params[p["name"]]
                        mat[key] = list(v) if isinstance(v, tuple) else v  # now on the panel, to edit
                        flags.append("%s not stored on the material ('%s'): the model's default %s used "
                                     "(and stored)" % (p["name"], key, _fmt(v)))
                res = mr.remap(model, params, SELF_MODEL, size=self.size)
                for name, v in res.values.items():
                    if name in N.PRINCIPLED_INPUTS:
                        note = N.set_principled_value(node, name, v)
                        if note:
                            flags.append(note)
                src_txt = ", ".join("%s %s" % (k, _fmt(v)) for k, v in params.items())
                dst_txt = ", ".join("%s %s" % (k, _fmt(v)) for k, v in res.values.items())
                lines += ["%s: %s (%s) -> Principled (%s)" % (mat.name, model, src_txt, dst_txt)]
                what = "%s -> Principled" % model
        except Exception as exc:  # matremap.Error / ValueError carry the library's message
            self.report({"ERROR"}, "%s: %s" % (model, exc))
            return {"CANCELLED"}
        lines.append("  outcome %s, relative RMSE %.4g, SSIM %.4f, %d renders, %.2f s%s" % (
            res.outcome, res.relative_rmse, res.ssim, res.renders, res.seconds,
            (" (%s)" % res.detail) if res.detail else ""))
        if res.outcome != "converged":  # at-bound, unreachable, local-minimum, under-resolved (docs/remap.md)
            flags.append("outcome '%s'%s" % (res.outcome, (": " + res.detail) if res.detail else ""))
        summary = "%s: %s, SSIM %.4f, relative RMSE %.3g" % (what, res.outcome, res.ssim, res.relative_rmse)
        _finish(self, context, "Remap %s" % what, lines, summary, flags)
        return {"FINISHED"}


class MATERIAL_PT_matremap(bpy.types.Panel):
    bl_label = "matremap"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    def draw(self, context):
        layout = self.layout
        s = context.scene.matremap
        mr = load_package(context)
        if mr is None:
            layout.label(text=package.error() or "matremap is not loaded", icon="ERROR")
            layout.label(text="Set the library in the add-on's preferences")
            return
        box = layout.box()
        box.label(text="Spec-gloss glTF material -> Principled BSDF")
        box.prop(s, "scope")
        box.prop(s, "method")
        box.prop(s, "mode")
        if s.mode == "NEW":
            box.prop(s, "suffix")
        box.prop(s, "save_dir")
        op = box.operator(MATREMAP_OT_convert_specgloss.bl_idname)
        op.scope, op.method, op.mode, op.suffix, op.save_dir = s.scope, s.method, s.mode, s.suffix, s.save_dir
        box = layout.box()
        box.label(text="Remap the Principled BSDF")
        box.prop(s, "model")
        box.prop(s, "direction")
        box.prop(s, "size")
        mat = context.object.active_material if context.object else None
        if mat is not None:
            for key in sorted(k for k in mat.keys() if k.startswith("matremap:%s:" % s.model)):
                box.prop(mat, '["%s"]' % key, text=key.split(":", 2)[2])
        op = box.operator(MATREMAP_OT_remap_principled.bl_idname)
        op.model, op.direction, op.size = s.model, s.direction, s.size
        if s.last_report:
            layout.label(text=s.last_report[:120])
            layout.label(text="details: Text Editor > '%s'" % REPORT_TEXT)


CLASSES = (MatremapPreferences, MatremapSettings, MATREMAP_OT_convert_specgloss, MATREMAP_OT_remap_principled,
           MATERIAL_PT_matremap)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Scene.matremap = PointerProperty(type=MatremapSettings)


def unregister():
    del bpy.types.Scene.matremap
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
