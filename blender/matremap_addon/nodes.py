"""Node-tree helpers: reading the spec-gloss tree Blender's glTF importer builds, and the Principled BSDF's inputs
across Blender 3.x (Principled v1) and 4.x (v2).

What Blender 3.4's importer builds for KHR_materials_pbrSpecularGlossiness (io_scene_gltf2,
blender/imp/gltf2_blender_KHR_materials_pbrSpecularGlossiness.py, printed from real imports in
docs/blender-addon.md): Glossy BSDF + Diffuse BSDF -> Add Shader -> (Emission add, alpha Mix Shader) -> Output;
  Diffuse Color   <- [diffuse texture Color] [x Mix MULTIPLY "Color Factor"]      or the diffuseFactor constant
  Glossy Color    <- [specGloss texture Color] [x Mix MULTIPLY "Specular Factor"] or the specularFactor constant
  Glossy/Diffuse Roughness <- Invert(Fac 1) <- [x Math MULTIPLY "Glossiness Factor"] <- specGloss texture Alpha,
                              or the constant 1 - glossinessFactor
  Normal          <- Normal Map <- normal texture (both BSDFs)
"""

import bpy

# Principled BSDF inputs by matremap's cycles-principled parameter: the 3.x name first, then 4.x's.
PRINCIPLED_INPUTS = {
    "base_color": ("Base Color",),
    "metallic": ("Metallic",),
    "specular": ("Specular", "Specular IOR Level"),
    "specular_tint": ("Specular Tint",),
    "roughness": ("Roughness",),
}


def principled_input(node, param):
    for name in PRINCIPLED_INPUTS[param]:
        sock = node.inputs.get(name)
        if sock is not None:
            return sock
    return None


def is_v2(node):
    """Blender 4.x's Principled v2 (Specular IOR Level, colour Specular Tint)."""
    return node.inputs.get("Specular IOR Level") is not None


def get_principled_value(node, param):
    """(value, note): the input's default value as matremap's parameter (floats or an RGB tuple); note is None
    or says why the value is not the whole story (linked input, a 4.x colour tint)."""
    sock = principled_input(node, param)
    if sock is None:
        return None, "%s: no such input on this Principled BSDF" % param
    note = None
    if sock.is_linked:
        note = "'%s' is driven by a link (%s); its unlinked value is used" % (sock.name, sock.links[0].from_node.name)
    val = sock.default_value
    if param == "base_color":
        return (float(val[0]), float(val[1]), float(val[2])), note
    if param == "specular_tint" and sock.type == "RGBA":  # 4.x: a colour; matremap's v1 takes a weight
        rgb = [float(v) for v in val[:3]]
        if max(rgb) - min(rgb) > 1e-6 or abs(rgb[0] - 1.0) > 1e-6:
            note = "'Specular Tint' is a colour in Blender 4.x; matremap's cycles-principled takes a weight: 0 used"
        return 0.0, note
    return float(val), note


def set_principled_value(node, param, value):
    """Sets the input's default value (an unlinked input only); returns None or a note saying what was skipped."""
    sock = principled_input(node, param)
    if sock is None:
        return "%s: no such input on this Principled BSDF" % param
    if sock.is_linked:
        return "'%s' is driven by a link (%s): not changed" % (sock.name, sock.links[0].from_node.name)
    if param == "base_color":
        v = value if isinstance(value, (tuple, list)) else (value, value, value)
        sock.default_value = (float(v[0]), float(v[1]), float(v[2]), 1.0)
    elif param == "specular_tint" and sock.type == "RGBA":
        if float(value) > 1e-6:
            return "'Specular Tint' is a colour in Blender 4.x: weight %.3g not set" % float(value)
    else:
        sock.default_value = float(value[0] if isinstance(value, (tuple, list)) else value)
    return None


def set_glTF_specular(node):
    """The metal-rough convention's dielectric F0 0.04: Specular 0.5 (3.x) or IOR 1.5 and level 0.5 (4.x)."""
    sock = principled_input(node, "specular")
    if sock is not None and not sock.is_linked:
        sock.default_value = 0.5
    if is_v2(node) and node.inputs.get("IOR") is not None:
        node.inputs["IOR"].default_value = 1.5
    tint = node.inputs.get("Specular Tint")
    if tint is not None and not tint.is_linked:
        tint.default_value = (1.0, 1.0, 1.0, 1.0) if tint.type == "RGBA" else 0.0


def find_principled(mat):
    """The Principled BSDF feeding the active material output (else the first one in the tree), or None."""
    if mat is None or not mat.use_nodes or mat.node_tree is None:
        return None
    nodes = mat.node_tree.nodes
    out = next((n for n in nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output), None)
    if out is not None:
        seen, todo = set(), [out]
        while todo:
            n = todo.pop()
            if n.name in seen:
                continue
            seen.add(n.name)
            if n.type == "BSDF_PRINCIPLED":
                return n
            for i in n.inputs:
                todo.extend(l.from_node for l in i.links)
    return next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)


# --- reading the importer's spec-gloss tree -------------------------------------------------------------------

class Const:
    def __init__(self, value):
        self.value = value  # a float or an RGB tuple

    def describe(self):
        return "constant %s" % (("%.4g" % self.value) if isinstance(self.value, float)
                                else "(%s)" % ", ".join("%.4g" % v for v in self.value))


class Tex:
    def __init__(self, node, channel, factor, invert=False):
        self.node = node          # the Image Texture node
        self.channel = channel    # "Color" or "Alpha"
        self.factor = factor      # a float or an RGB tuple the texel is multiplied by
        self.invert = invert      # the value is 1 - texel x factor (a roughness map read as glossiness)

    def describe(self):
        img = self.node.image
        f = self.factor
        fs = "" if f in (1.0, (1.0, 1.0, 1.0)) else " x %s" % (("%.4g" % f) if isinstance(f, float)
                                                                  else "(%s)" % ", ".join("%.4g" % v for v in f))
        return "%s%s of %s (%dx%d, %s)%s" % ("1 - " if self.invert else "", self.channel.lower(), img.name,
                                             img.size[0], img.size[1], img.colorspace_settings.name, fs)


class Unsupported(Exception):
    pass


def _const_of(sock):
    v = sock.default_value
    try:
        return tuple(float(x) for x in v[:3])
    except TypeError:
        return float(v)


def _mul(a, b):
    if isinstance(a, tuple) and isinstance(b, tuple):
        return tuple(x * y for x, y in zip(a, b))
    if isinstance(a, tuple):
        return tuple(x * b for x in a)
    if isinstance(b, tuple):
        return tuple(a * y for y in b)
    return a * b


def _mix_inputs(node):
    """The two colour inputs of a MULTIPLY Mix (ShaderNodeMix, RGBA) or MixRGB node at factor 1, else None."""
    if node.type == "MIX" and getattr(node, "data_type", "") == "RGBA" and node.blend_type == "MULTIPLY":
        fac = node.inputs[0]
        a, b = node.inputs[6], node.inputs[7]
    elif node.type == "MIX_RGB" and node.blend_type == "MULTIPLY":
        fac = node.inputs["Fac"]
        a, b = node.inputs["Color1"], node.inputs["Color2"]
    else:
        return None
    if fac.is_linked or abs(float(fac.default_value) - 1.0) > 1e-6:
        return None
    return a, b


def trace(sock):
    """What drives SOCK: Const or Tex (a texture times constant factors); Unsupported says what else does."""
    factor = 1.0
    while True:
        if not sock.is_linked:
            return Const(_mul(_const_of(sock), factor) if factor != 1.0 else _const_of(sock))
        link = sock.links[0]
        node = link.from_node
        if node.type == "REROUTE":
            sock = node.inputs[0]
            continue
        if node.type == "TEX_IMAGE":
            if node.image is None:
                raise Unsupported("image texture node '%s' has no image" % node.name)
            return Tex(node, "Alpha" if link.from_socket.name == "Alpha" else "Color", factor)
        pair = _mix_inputs(node)
        if pair is None and node.type == "MATH" and node.operation == "MULTIPLY":
            pair = node.inputs[0], node.inputs[1]
        if pair is not None:
            a, b = pair
            if a.is_linked and b.is_linked:
                raise Unsupported("'%s' multiplies two linked inputs" % node.name)
            linked, const = (a, b) if a.is_linked else (b, a)
            factor = _mul(factor, _const_of(const))
            sock = linked
            continue
        raise Unsupported("'%s' (%s) drives %s" % (node.name, node.type, sock.name))


class SpecGlossPrincipled:
    """Blender 4.1+'s importer (glTF-Blender-IO #2127): one Principled BSDF v2 with IOR 1000 (so F0 = Specular
    Tint), Base Color <- diffuse, Specular Tint <- specular, Roughness <- the alpha of a copy of the specGloss
    texture holding 1 - glossiness x factor (or the constant 1 - glossinessFactor)."""
    kind = "principled"

    def __init__(self, node):
        self.shader = node
        self.diffuse = trace(node.inputs["Base Color"])
        self.specular = trace(node.inputs["Specular Tint"])
        if isinstance(self.specular, Const) and not isinstance(self.specular.value, tuple):
            self.specular = Const((self.specular.value,) * 3)
        r = trace(node.inputs["Roughness"])
        if isinstance(r, Const):
            self.glossiness = Const(1.0 - (sum(r.value) / 3.0 if isinstance(r.value, tuple) else r.value))
        else:
            r.invert = True
            if isinstance(r.factor, tuple):
                r.factor = sum(r.factor) / 3.0
            self.glossiness = r

    def textures(self):
        return [s for s in (self.diffuse, self.specular, self.glossiness) if isinstance(s, Tex)]

    def inputs(self):
        return ("Base Color", "Specular Tint", "Roughness", "Metallic")


def is_specgloss_principled(node):
    """The 4.1+ importer's mark: IOR >= 100 (1000 there) with Specular Tint a link or a colour."""
    ior, tint = node.inputs.get("IOR"), node.inputs.get("Specular Tint")
    if ior is None or tint is None or ior.is_linked or ior.default_value < 100:
        return False
    return tint.is_linked or tint.type == "RGBA"


class SpecGloss:
    """One spec-gloss shading group of a material: the Add Shader of a Diffuse and a Glossy BSDF."""
    kind = "add"

    def __init__(self, add, diffuse, glossy):
        self.add, self.diffuse_bsdf, self.glossy_bsdf = add, diffuse, glossy
        self.shader = add
        self.diffuse = trace(diffuse.inputs["Color"])
        self.specular = trace(glossy.inputs["Color"])
        rough = glossy.inputs["Roughness"]
        if not rough.is_linked:
            self.glossiness = Const(1.0 - float(rough.default_value))
        else:
            node = rough.links[0].from_node
            fac = node.inputs["Fac"] if node.type == "INVERT" else None
            if fac is None or fac.is_linked or abs(fac.default_value - 1) > 1e-6:
                raise Unsupported("the Glossy BSDF's roughness comes from '%s' (%s), not the importer's "
                                  "Invert (Gloss to Rough)" % (node.name, node.type))
            g = trace(node.inputs["Color"])
            if isinstance(g, Const) and isinstance(g.value, tuple):  # the Invert's Color input is the gloss
                g = Const(sum(g.value) / 3.0)
            self.glossiness = g
        if isinstance(self.glossiness, Tex) and isinstance(self.glossiness.factor, tuple):
            self.glossiness.factor = sum(self.glossiness.factor) / 3.0

    def textures(self):
        return [s for s in (self.diffuse, self.specular, self.glossiness) if isinstance(s, Tex)]


def find_specgloss(mat):
    """The spec-gloss groups of MAT's tree (a list, maybe empty) and the notes on groups that could not be read."""
    groups, notes = [], []
    if mat is None or not mat.use_nodes or mat.node_tree is None:
        return groups, notes
    for node in mat.node_tree.nodes:
        if node.type == "BSDF_PRINCIPLED" and is_specgloss_principled(node):
            try:
                groups.append(SpecGlossPrincipled(node))
            except Unsupported as exc:
                notes.append("%s: not the glTF importer's spec-gloss Principled (IOR %g): %s"
                             % (mat.name, node.inputs["IOR"].default_value, exc))
            continue
        if node.type not in ("ADD_SHADER", "MIX_SHADER"):
            continue
        srcs = [i.links[0].from_node for i in node.inputs if i.is_linked and i.type == "SHADER"]
        dif = [n for n in srcs if n.type == "BSDF_DIFFUSE"]
        glo = [n for n in srcs if n.type in ("BSDF_GLOSSY", "BSDF_ANISOTROPIC")]
        if node.type == "MIX_SHADER" or len(dif) != 1 or len(glo) != 1:
            continue
        try:
            groups.append(SpecGloss(node, dif[0], glo[0]))
        except Unsupported as exc:
            notes.append("%s: not the glTF importer's spec-gloss tree: %s" % (mat.name, exc))
    return groups, notes


def upstream(node):
    """Every node whose output reaches NODE (not NODE itself)."""
    seen, todo, out = set(), [node], []
    while todo:
        n = todo.pop()
        for i in n.inputs:
            for l in i.links:
                m = l.from_node
                if m.name not in seen:
                    seen.add(m.name)
                    out.append(m)
                    todo.append(m)
    return out


def remove_dangling(tree, names):
    """Removes, from the nodes named NAMES, those none of whose outputs is linked (repeatedly). (Names, not nodes:
    a Python node object must not be touched once its node is removed.)"""
    names = set(names)
    changed = True
    while changed:
        changed = False
        for name in list(names):
            n = tree.nodes.get(name)
            if n is None:
                names.discard(name)
                continue
            if not any(o.is_linked for o in n.outputs):
                tree.nodes.remove(n)
                names.discard(name)
                changed = True


def separate_rgb_node(tree):
    """Separate Color (3.3+) or Separate RGB (older): outputs 0, 1, 2 are R, G, B either way."""
    try:
        return tree.nodes.new("ShaderNodeSeparateColor")
    except RuntimeError:
        return tree.nodes.new("ShaderNodeSeparateRGB")


def bpy_version():
    return bpy.app.version
