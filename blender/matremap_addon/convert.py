"""Operator (a)'s work: a spec-gloss material built by Blender's glTF importer -> a Principled BSDF with converted
textures (matremap.spec2metal on the texels), in glTF's metallic-roughness layout."""

import os

import bpy
import numpy as np

from . import nodes as N

SRGB_NAMES = ("sRGB",)
LINEAR_NAMES = ("Non-Color", "Linear", "Linear Rec.709", "Raw", "Linear CIE-XYZ E", "Linear Rec.2020")


class Flagged(Exception):
    pass


def image_array(img, notes):
    """The image's texels as float32 (H, W, 4), straight alpha, in Blender's row order (bottom row first)."""
    w, h = img.size
    if w == 0 or h == 0:
        raise Flagged("image '%s' has no pixels (missing file '%s'?)" % (img.name, img.filepath))
    buf = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    return buf.reshape(h, w, 4)


def decode_color(mr, img, rgb, notes):
    """Linear RGB from an image's colour texels: byte images tagged sRGB are decoded; float images and
    non-colour/linear ones are taken as they are (Blender keeps float buffers scene-linear)."""
    cs = img.colorspace_settings.name
    if img.is_float:
        return rgb
    if cs in SRGB_NAMES:
        return mr.srgb_to_linear(np.ascontiguousarray(rgb))
    if cs not in LINEAR_NAMES:
        notes.append("image '%s' is in colour space '%s': read as sRGB" % (img.name, cs))
        return mr.srgb_to_linear(np.ascontiguousarray(rgb))
    return rgb


def _resized(img, w, h, notes):
    if tuple(img.size) == (w, h):
        return img, False
    notes.append("image '%s' (%dx%d) resampled to %dx%d to match the other maps" % (img.name, img.size[0],
                                                                                    img.size[1], w, h))
    tmp = img.copy()
    tmp.scale(w, h)
    return tmp, True


def source_array(mr, src, w, h, channels, notes):
    """SRC (Const or Tex) as float32 (h, w, channels) linear values."""
    if isinstance(src, N.Const):
        v = src.value
        if channels == 3:
            v = v if isinstance(v, tuple) else (v, v, v)
            return np.broadcast_to(np.asarray(v, dtype=np.float32), (h, w, 3)).copy()
        v = sum(v) / 3.0 if isinstance(v, tuple) else v
        return np.full((h, w), v, dtype=np.float32)
    img, tmp = _resized(src.node.image, w, h, notes)
    try:
        px = image_array(img, notes)
    finally:
        if tmp:
            bpy.data.images.remove(img)
    if src.channel == "Alpha":
        a = px[:, :, 3]
        out = np.repeat(a[:, :, None], 3, axis=2) if channels == 3 else a.copy()
    else:
        rgb = decode_color(mr, src.node.image, np.ascontiguousarray(px[:, :, :3]), notes)
        out = rgb if channels == 3 else rgb.mean(axis=2)
    f = src.factor
    if channels == 3:
        out = out * np.asarray(f if isinstance(f, tuple) else (f, f, f), dtype=np.float32)
    else:
        out = out * (sum(f) / 3.0 if isinstance(f, tuple) else f)
    if getattr(src, "invert", False):
        out = 1.0 - out
    return np.ascontiguousarray(np.clip(out, 0.0, 1.0), dtype=np.float32)


def _vector_source(tex_node):
    v = tex_node.inputs.get("Vector")
    if v is None or not v.is_linked:
        return None
    return v.links[0].from_socket


def new_image(name, w, h, pixels_rgba, colorspace):
    img = bpy.data.images.new(name, w, h, alpha=True, float_buffer=False)
    img.colorspace_settings.name = colorspace
    img.pixels.foreach_set(np.ascontiguousarray(pixels_rgba, dtype=np.float32).ravel())
    img.update()
    return img


def store_image(img, save_dir):
    """Saves IMG as PNG in SAVE_DIR (a .blend-relative path is kept) or packs it into the .blend."""
    if save_dir:
        path = os.path.join(save_dir, bpy.path.clean_name(img.name) + ".png")
        os.makedirs(save_dir, exist_ok=True)
        img.filepath_raw = path
        img.file_format = "PNG"
        img.save()
        if bpy.data.filepath:
            img.filepath = bpy.path.relpath(path)
        return "saved %s" % path
    img.pack()
    return "packed"


TOL = 2.0 / 255.0  # linear reflectance a texel may miss by in the round trip before it is flagged


def round_trip(mr, base, metal, rough, dif, spec):
    """How many texels metal2spec of the result misses (diffuse or specular by more than TOL), and the worst miss:
    the texels (zero or coloured dielectric specular, say) the metal-rough model cannot hold."""
    back = mr.metal2spec(np.ascontiguousarray(base), np.ascontiguousarray(metal), np.ascontiguousarray(rough))
    err = np.maximum(np.abs(back["diffuse"][:, :, :3] - dif).max(axis=2),
                     np.abs(back["specular"][:, :, :3] - spec).max(axis=2))
    return int(np.count_nonzero(err > TOL)), float(err.max())


def summarize(name, a):
    a = np.asarray(a)
    return "%s %.3f..%.3f (mean %.3f)" % (name, float(a.min()), float(a.max()), float(a.mean()))


def convert_material(mr, mat, method, mode, suffix, save_dir, log):
    """Converts MAT's spec-gloss group(s). Returns (material converted to, flags list); raises Flagged when
    nothing could be done. LOG gets the detail lines."""
    groups, notes = N.find_specgloss(mat)
    if not groups:
        raise Flagged("; ".join(notes) if notes else "%s: no Diffuse + Glossy BSDF pair (not a spec-gloss "
                      "material from the glTF importer)" % mat.name)
    if len(groups) > 1:
        notes.append("%d spec-gloss shaders: only '%s' converted" % (len(groups), groups[0].shader.name))
    g = groups[0]
    log.append("  diffuse: %s" % g.diffuse.describe())
    log.append("  specular: %s" % g.specular.describe())
    log.append("  glossiness: %s" % g.glossiness.describe())
    texs = g.textures()
    if texs:
        w = max(t.node.image.size[0] for t in texs)
        h = max(t.node.image.size[1] for t in texs)
        vecs = {repr(_vector_source(t.node)) for t in texs}
        if len(vecs) > 1:
            notes.append("the maps use different texture coordinates: the result uses the first map's")
    else:
        w = h = 1
    dif = source_array(mr, g.diffuse, w, h, 3, notes)
    spec = source_array(mr, g.specular, w, h, 3, notes)
    gloss = source_array(mr, g.glossiness, w, h, 1, notes)
    res = mr.spec2metal(dif, spec, gloss, method=method)
    base = np.asarray(res["base_color"], dtype=np.float32).reshape(h, w, -1)[:, :, :3]
    metal = np.asarray(res["metallic"], dtype=np.float32).reshape(h, w)
    rough = np.asarray(res["roughness"], dtype=np.float32).reshape(h, w)
    log.append("  spec2metal %s on %dx%d: %s; %s; %s" % (method, w, h, summarize("base colour", base),
                                                         summarize("metallic", metal), summarize("roughness", rough)))
    clipped = int(np.count_nonzero(np.asarray(res["base_color"])[:, :, :3] > 1.0))
    if clipped:
        notes.append("%s: %d base colour values above 1 clipped" % (mat.name, clipped))
    off, worst = round_trip(mr, base, metal, rough, dif, spec)
    if off:
        notes.append("%s: %d of %d texels (%.1f%%) not reproduced by metal-rough: converting back misses their "
                     "diffuse or specular by more than %.3g (at most %.3g)" % (mat.name, off, w * h,
                                                                              100.0 * off / (w * h), TOL, worst))
    log.append("  round trip (metal2spec of the result): %d texels off by more than %.3g, worst %.3g"
               % (off, TOL, worst))
    for key, val in res.items():  # whatever else the library says (flags, counts)
        if key in ("base_color", "metallic", "roughness"):
            continue
        if isinstance(val, np.ndarray) and val.size > 1:
            nz = int(np.count_nonzero(val))
            log.append("  %s: %d of %d texels non-zero" % (key, nz, val.size if val.ndim < 3 else val.shape[0] *
                                                            val.shape[1]))
            if "flag" in key and nz:
                notes.append("%s: %d texels flagged by spec2metal (%s)" % (mat.name, nz, key))
        else:
            log.append("  %s: %s" % (key, val))
            if "flag" in key and val:
                notes.append("%s: spec2metal %s = %s" % (mat.name, key, val))

    # the material: a copy (NEW) or this one (REPLACE)
    if mode == "NEW":
        target = mat.copy()
        target.name = mat.name + suffix
        mat.use_fake_user = True
    else:
        target = mat
    tree = target.node_tree
    if g.kind == "add":  # Diffuse + Glossy -> Add Shader: a new Principled takes the Add Shader's place
        add = tree.nodes[g.add.name]
        old_upstream = [n.name for n in N.upstream(add)]
        remove = [add.name, g.diffuse_bsdf.name, g.glossy_bsdf.name]
        glo_bsdf = tree.nodes[g.glossy_bsdf.name]
        p = tree.nodes.new("ShaderNodeBsdfPrincipled")
        p.location = (add.location.x - 60, add.location.y)
        for link in list(add.outputs[0].links):
            tree.links.new(p.outputs[0], link.to_socket)
        normal = glo_bsdf.inputs["Normal"]
        if normal.is_linked:
            tree.links.new(normal.links[0].from_socket, p.inputs["Normal"])
    else:  # 4.1+'s Principled with IOR 1000: this Principled, its colour, tint and roughness inputs rewired
        p = tree.nodes[g.shader.name]
        old_upstream, remove = [], []
        for name in g.inputs():
            sock = p.inputs.get(name)
            for link in list(sock.links) if sock is not None else ():
                old_upstream += [link.from_node.name] + [n.name for n in N.upstream(link.from_node)]
                tree.links.remove(link)
        if p.inputs.get("IOR") is not None:
            p.inputs["IOR"].default_value = 1.5
    p.name = p.label = "matremap Principled"
    N.set_glTF_specular(p)
    images = []
    if not texs:
        N.set_principled_value(p, "base_color", tuple(float(x) for x in base[0, 0]))
        N.set_principled_value(p, "metallic", float(metal[0, 0]))
        N.set_principled_value(p, "roughness", float(rough[0, 0]))
        log.append("  constants: Base Color (%.4g, %.4g, %.4g), Metallic %.4g, Roughness %.4g"
                   % (base[0, 0, 0], base[0, 0, 1], base[0, 0, 2], metal[0, 0], rough[0, 0]))
    else:
        vec = _vector_source(texs[0].node)
        if vec is not None:
            vec = tree.nodes[vec.node.name].outputs[vec.name]
        alpha = np.ones((h, w), dtype=np.float32)
        alpha_links = []
        if isinstance(g.diffuse, N.Tex):
            old = tree.nodes[g.diffuse.node.name]
            alpha_links = [l.to_socket for l in old.outputs["Alpha"].links]
            if alpha_links:
                alpha = source_array(mr, N.Tex(g.diffuse.node, "Alpha", 1.0), w, h, 1, notes)
        bc_px = np.concatenate([mr.linear_to_srgb(np.ascontiguousarray(np.clip(base, 0, 1))),
                                alpha[:, :, None]], axis=2)
        mr_px = np.stack([np.ones_like(rough), rough, metal, np.ones_like(rough)], axis=2)
        bc_img = new_image("%s_baseColor" % target.name, w, h, bc_px, "sRGB")
        mr_img = new_image("%s_metallicRoughness" % target.name, w, h, mr_px, "Non-Color")
        images = [bc_img, mr_img]
        for img in images:
            log.append("  image %s (%dx%d): %s" % (img.name, w, h, store_image(img, save_dir)))
        x, y = p.location.x - 600, p.location.y
        bc = tree.nodes.new("ShaderNodeTexImage")
        bc.name = bc.label = "matremap BASE COLOR"
        bc.image = bc_img
        bc.location = (x, y)
        tree.links.new(bc.outputs["Color"], p.inputs["Base Color"])
        for s in alpha_links:
            tree.links.new(bc.outputs["Alpha"], s)
        mrn = tree.nodes.new("ShaderNodeTexImage")
        mrn.name = mrn.label = "matremap METALLIC ROUGHNESS"
        mrn.image = mr_img
        mrn.location = (x, y - 300)
        sep = N.separate_rgb_node(tree)
        sep.name = "matremap Separate"
        sep.location = (x + 300, y - 300)
        tree.links.new(mrn.outputs["Color"], sep.inputs[0])
        tree.links.new(sep.outputs[1], p.inputs["Roughness"])   # glTF: roughness in G
        tree.links.new(sep.outputs[2], p.inputs["Metallic"])    # metallic in B
        if vec is not None:
            tree.links.new(vec, bc.inputs["Vector"])
            tree.links.new(vec, mrn.inputs["Vector"])
    for name in remove:
        tree.nodes.remove(tree.nodes[name])
    N.remove_dangling(tree, old_upstream)
    if mode == "NEW":
        for ob in bpy.data.objects:
            for slot in getattr(ob, "material_slots", ()):
                if slot.material == mat:
                    slot.material = target
    return target, images, notes
