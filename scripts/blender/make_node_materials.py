"""Write data/blender/node_materials.blend: uniform node materials that Blender's glTF exporter cannot export
faithfully (issue 29, item 6; docs/evaluation-renderers.md).

    blender -b --factory-startup --python-exit-code 3 --python scripts/blender/make_node_materials.py -- \
        -o data/blender/node_materials.blend

Every material is uniform (no textures, no texture coordinates), ends in a Material Output (target ALL) and has a
fake user, so the file holds nothing but the materials (no objects, no scene content beyond Blender's empty default
scene). The node values are fixed constants: rerunning the script writes a file that renders the same.

Materials (colours are linear RGB):
  DiffuseGlossyAdd     Diffuse BSDF (0.50, 0.12, 0.08) + Glossy BSDF (0.08 grey, roughness 0.25, GGX) through an
                       Add Shader: a red plastic whose coat is a Fresnel-less constant 8 % mirror lobe.
  LayerWeightMix       Layer Weight (Blend 0.35) Fresnel output as the factor of a Mix Shader from a Diffuse BSDF
                       (0.06, 0.22, 0.60) to a white Glossy BSDF (roughness 0.2, GGX): a blue glazed ceramic.
  TintedGlossyMetal    a Glossy BSDF alone, colour (0.90, 0.55, 0.35), roughness 0.3 (GGX): a copper-like metal
                       with no Fresnel (the colour at every angle).
  ConstantMixGlossy    a Mix Shader with the constant factor 0.3 from a Diffuse BSDF (0.15, 0.45, 0.12) to a white
                       Glossy BSDF (roughness 0.4, GGX): a green satin.
  RampPrincipled       a Principled BSDF (roughness 0.35, metallic 0) whose Base Color comes from a ColorRamp
                       (black -> orange (1.0, 0.35, 0.02) at positions 0 and 1, linear) reading a Value node 0.6:
                       uniform (0.6, 0.21, 0.012), but through nodes the exporter does not evaluate.
And one control that the exporter does state (it checks the export -> import -> render path itself):
  ControlPrincipled    a plain Principled BSDF, base colour (0.55, 0.35, 0.12), metallic 0, specular 0.5 (glTF's
                       ior 1.5), roughness 0.3, GGX.
"""

import os
import sys

import bpy


def fail(msg, code=2):
    sys.stderr.write("make_node_materials: %s\n" % msg)
    sys.stderr.flush()
    os._exit(code)


def new_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    mat.use_fake_user = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.name = "Material Output"
    out.target = "ALL"
    out.location = (400, 0)
    return mat, nt, out


def node(nt, kind, name, x, y, **inputs):
    n = nt.nodes.new(kind)
    n.name = name
    n.label = name
    n.location = (x, y)
    for key, value in inputs.items():
        sock = n.inputs[key.replace("_", " ")]
        if isinstance(value, (tuple, list)) and len(value) == 3:
            value = tuple(value) + (1.0,)
        sock.default_value = value
    return n


def diffuse(nt, name, color, x, y):
    return node(nt, "ShaderNodeBsdfDiffuse", name, x, y, Color=color, Roughness=0.0)


def glossy(nt, name, color, roughness, x, y):
    g = node(nt, "ShaderNodeBsdfGlossy", name, x, y, Color=color, Roughness=roughness)
    g.distribution = "GGX"
    return g


def diffuse_glossy_add():
    mat, nt, out = new_material("DiffuseGlossyAdd")
    d = diffuse(nt, "Diffuse BSDF", (0.50, 0.12, 0.08), -300, 150)
    g = glossy(nt, "Glossy BSDF", (0.08, 0.08, 0.08), 0.25, -300, -100)
    add = node(nt, "ShaderNodeAddShader", "Add Shader", 100, 0)
    nt.links.new(d.outputs["BSDF"], add.inputs[0])
    nt.links.new(g.outputs["BSDF"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Surface"])


def layer_weight_mix():
    mat, nt, out = new_material("LayerWeightMix")
    lw = node(nt, "ShaderNodeLayerWeight", "Layer Weight", -300, 250, Blend=0.35)
    d = diffuse(nt, "Diffuse BSDF", (0.06, 0.22, 0.60), -300, 50)
    g = glossy(nt, "Glossy BSDF", (1.0, 1.0, 1.0), 0.2, -300, -200)
    mix = node(nt, "ShaderNodeMixShader", "Mix Shader", 100, 0)
    nt.links.new(lw.outputs["Fresnel"], mix.inputs["Fac"])
    nt.links.new(d.outputs["BSDF"], mix.inputs[1])
    nt.links.new(g.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])


def tinted_glossy_metal():
    mat, nt, out = new_material("TintedGlossyMetal")
    g = glossy(nt, "Glossy BSDF", (0.90, 0.55, 0.35), 0.3, -100, 0)
    nt.links.new(g.outputs["BSDF"], out.inputs["Surface"])


def constant_mix_glossy():
    mat, nt, out = new_material("ConstantMixGlossy")
    d = diffuse(nt, "Diffuse BSDF", (0.15, 0.45, 0.12), -300, 100)
    g = glossy(nt, "Glossy BSDF", (1.0, 1.0, 1.0), 0.4, -300, -150)
    mix = node(nt, "ShaderNodeMixShader", "Mix Shader", 100, 0, Fac=0.3)
    nt.links.new(d.outputs["BSDF"], mix.inputs[1])
    nt.links.new(g.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])


def ramp_principled():
    mat, nt, out = new_material("RampPrincipled")
    v = nt.nodes.new("ShaderNodeValue")
    v.name = v.label = "Value"
    v.location = (-600, 100)
    v.outputs["Value"].default_value = 0.6
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.name = ramp.label = "ColorRamp"
    ramp.location = (-400, 100)
    cr = ramp.color_ramp
    cr.interpolation = "LINEAR"
    cr.color_mode = "RGB"
    cr.elements[0].position = 0.0
    cr.elements[0].color = (0.0, 0.0, 0.0, 1.0)
    cr.elements[1].position = 1.0
    cr.elements[1].color = (1.0, 0.35, 0.02, 1.0)
    p = node(nt, "ShaderNodeBsdfPrincipled", "Principled BSDF", -100, 0, Metallic=0.0, Roughness=0.35,
             Specular=0.5)
    p.distribution = "GGX"
    nt.links.new(v.outputs["Value"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], p.inputs["Base Color"])
    nt.links.new(p.outputs["BSDF"], out.inputs["Surface"])


def control_principled():
    mat, nt, out = new_material("ControlPrincipled")
    p = node(nt, "ShaderNodeBsdfPrincipled", "Principled BSDF", -100, 0, Base_Color=(0.55, 0.35, 0.12),
             Metallic=0.0, Specular=0.5, Roughness=0.3)
    p.distribution = "GGX"
    nt.links.new(p.outputs["BSDF"], out.inputs["Surface"])


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 2 or argv[0] != "-o":
        fail("usage: blender -b --factory-startup --python make_node_materials.py -- -o OUT.blend", 1)
    out = os.path.abspath(argv[1])
    if not out.endswith(".blend"):
        fail("output '%s' must end in .blend" % argv[1])
    if not os.path.isdir(os.path.dirname(out)):
        fail("output directory '%s' does not exist" % os.path.dirname(out))
    # Start from an empty file: no default cube, camera, light or material.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for coll in (bpy.data.materials, bpy.data.meshes, bpy.data.worlds):
        for block in list(coll):
            coll.remove(block)
    diffuse_glossy_add()
    layer_weight_mix()
    tinted_glossy_metal()
    constant_mix_glossy()
    ramp_principled()
    control_principled()
    tmp = "%s.tmp-%d.blend" % (out[:-6], os.getpid())
    bpy.ops.wm.save_as_mainfile(filepath=tmp, compress=True, copy=True)
    os.replace(tmp, out)
    print("make_node_materials: wrote %s (%s)" % (out, ", ".join(m.name for m in bpy.data.materials)), flush=True)


try:
    main()
except SystemExit as e:
    os._exit(e.code if isinstance(e.code, int) else 1)
except Exception as e:  # noqa: BLE001
    import traceback
    traceback.print_exc()
    fail("internal error: %s" % e, 3)
