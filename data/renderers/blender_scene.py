"""matremap's fit scene in Blender: the pieces both Blender front ends build it from.

Used (imported through sys.path) by data/renderers/blender_server.py, the long-lived renderer server of
/work/notes/protocol29.md style requests, and by scripts/cycles_fit_scene.py, the one-shot Cycles peer
(docs/cycles-peer.md). The mapping, measured in docs/cycles-peer.md with Blender 3.4.1:

  * matremap's coordinates are Blender's (both right-handed; +y up is the camera's own up, so the fit
    scene's camera at (0, 0, 4) looking at the origin has no rotation);
  * the sphere is one Geometry Nodes point (Points -> Set Material) that Cycles 3.1+ ray-traces as an
    exact sphere, or (cycles_fit_scene.py --geometry icosphere) a smooth icosphere mesh;
  * a point light of radius 0 and Power P watts has radiant intensity P / (4 pi) W/sr;
  * black world of strength 0, direct light only (every bounce count 0), box pixel filter, no clamping,
    denoising or adaptive sampling, Standard view transform.
"""

import math

import bpy
from mathutils import Matrix, Vector

# Cycles' point light: Power P watts (radius 0) has radiant intensity P / (4 pi) W/sr (docs/cycles-peer.md).
WATTS_PER_W_SR = 4.0 * math.pi
ICO_SUBDIVISIONS = 7

# Blender 3.x Principled BSDF (v1) inputs the fit scene sets away from the node's defaults, besides the
# model's own (Base Color, Metallic, Specular, Specular Tint, Roughness): lobes a fit scene does not model.
PRINCIPLED_OFF = (("Subsurface", 0.0), ("Sheen", 0.0), ("Clearcoat", 0.0), ("Transmission", 0.0),
                  ("Emission", (0.0, 0.0, 0.0, 1.0)))


def clear_scene():
    """Removes every object, mesh, light, camera and material (the factory start-up's cube, lamp, camera)."""
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    for coll in (bpy.data.meshes, bpy.data.lights, bpy.data.cameras, bpy.data.materials):
        for block in list(coll):
            coll.remove(block)


def make_black_world(scene):
    """A world that neither lights nor shows: background colour 0, strength 0."""
    world = bpy.data.worlds.new("FitWorld")
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        bg.inputs["Strength"].default_value = 0.0
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    return world


class Sphere:
    """The sphere object. geometry "points": a mesh object whose Geometry Nodes modifier outputs one point
    (centre, radius, material set on the nodes), which Cycles (3.1+) renders as an exact ray-traced sphere;
    "icosphere": a smooth-shaded icosphere mesh of radius 1, placed and scaled by the object."""

    def __init__(self, scene, geometry, material, center=(0.0, 0.0, 0.0), radius=1.0):
        import bmesh
        self.geometry = geometry
        mesh = bpy.data.meshes.new("FitSphere")
        if geometry == "icosphere":
            bm = bmesh.new()
            # Blender 3.0+ takes `radius` (2.8x called it `diameter` but meant the radius).
            try:
                bmesh.ops.create_icosphere(bm, subdivisions=ICO_SUBDIVISIONS, radius=1.0)
            except TypeError:
                bmesh.ops.create_icosphere(bm, subdivisions=ICO_SUBDIVISIONS, diameter=1.0)
            bm.to_mesh(mesh)
            bm.free()
            mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
            mesh.update()
        mesh.materials.append(material)
        self.object = bpy.data.objects.new("FitSphere", mesh)
        scene.collection.objects.link(self.object)
        self.points = self.set_material_node = None
        if geometry == "points":
            ng = bpy.data.node_groups.new("FitSpherePoint", "GeometryNodeTree")
            if hasattr(ng, "interface"):  # Blender 4.x
                ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
            else:
                ng.outputs.new("NodeSocketGeometry", "Geometry")
            out = ng.nodes.new("NodeGroupOutput")
            self.points = ng.nodes.new("GeometryNodePoints")
            self.points.inputs["Count"].default_value = 1
            self.set_material_node = ng.nodes.new("GeometryNodeSetMaterial")
            ng.links.new(self.points.outputs["Geometry"], self.set_material_node.inputs["Geometry"])
            ng.links.new(self.set_material_node.outputs["Geometry"], out.inputs[0])
            mod = self.object.modifiers.new("FitSpherePoint", "NODES")
            mod.node_group = ng
        self.material = None
        self.center = self.radius = None
        self.set_material(material)
        self.place(center, radius)

    def set_material(self, material):
        if material is self.material:
            return
        self.object.data.materials[0] = material
        if self.set_material_node is not None:
            self.set_material_node.inputs["Material"].default_value = material
        self.material = material

    def place(self, center, radius):
        center = tuple(float(c) for c in center)
        radius = float(radius)
        if (center, radius) == (self.center, self.radius):
            return
        if self.points is not None:
            self.points.inputs["Position"].default_value = center
            self.points.inputs["Radius"].default_value = radius
        else:
            self.object.location = center
            self.object.scale = (radius, radius, radius)
        self.center, self.radius = center, radius


def look_at_matrix(position, target, up):
    """The camera's world matrix: at `position`, local -z towards `target`, local +y in the plane of `up`.
    Raises ValueError when the frame is degenerate (target at the position, up along the view)."""
    eye = Vector(position)
    forward = Vector(target) - eye
    if forward.length == 0.0:
        raise ValueError("camera target equals its position")
    z = -forward.normalized()
    x = Vector(up).cross(z)
    if x.length < 1e-12:
        raise ValueError("camera up is parallel to the view direction (or zero)")
    x.normalize()
    y = z.cross(x)
    return Matrix(((x[0], y[0], z[0], eye[0]),
                   (x[1], y[1], z[1], eye[1]),
                   (x[2], y[2], z[2], eye[2]),
                   (0.0, 0.0, 0.0, 1.0)))


def make_camera(scene, position, target, up, fov_y_deg):
    """A perspective camera with a vertical field of view (sensor fit VERTICAL), made the scene's camera."""
    cam_data = bpy.data.cameras.new("FitCamera")
    cam_data.type = "PERSP"
    cam_data.sensor_fit = "VERTICAL"
    cam_data.lens_unit = "FOV"
    cam_data.clip_start = 0.01
    cam_data.clip_end = 100.0
    cam = bpy.data.objects.new("FitCamera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    set_camera(cam, position, target, up, fov_y_deg)
    return cam


def set_camera(cam, position, target, up, fov_y_deg):
    matrix = look_at_matrix(position, target, up)
    if cam.matrix_world != matrix:
        cam.matrix_world = matrix
    angle = math.radians(fov_y_deg)
    if cam.data.angle_y != angle:
        cam.data.angle_y = angle


def make_point_light(scene, name, position, intensity, power=None):
    """A point light of radius 0 at `position` with RGB radiant intensity `intensity` (W/sr)."""
    light = bpy.data.objects.new(name, bpy.data.lights.new(name, type="POINT"))
    light.data.shadow_soft_size = 0.0
    scene.collection.objects.link(light)
    set_point_light(light, position, intensity, power)
    return light


def set_point_light(light, position, intensity, power=None):
    """Power = 4 pi max(I) W, colour = I / max(I); `power` (watts, white) overrides (calibration only)."""
    peak = max(float(v) for v in intensity)
    if power is not None:
        energy, color = float(power), (1.0, 1.0, 1.0)
    elif peak > 0.0:
        energy, color = WATTS_PER_W_SR * peak, tuple(float(v) / peak for v in intensity)
    else:
        energy, color = 0.0, (1.0, 1.0, 1.0)
    if light.data.energy != energy:
        light.data.energy = energy
    if tuple(light.data.color) != color:
        light.data.color = color
    if tuple(light.location) != tuple(float(p) for p in position):
        light.location = position


def make_principled_material(name):
    """A material whose output's Surface is a Principled BSDF (GGX); returns (material, bsdf node)."""
    mat, bsdf = _material_with(name, "ShaderNodeBsdfPrincipled")
    bsdf.distribution = "GGX"
    for socket, value in PRINCIPLED_OFF:
        bsdf.inputs[socket].default_value = value
    return mat, bsdf


def set_principled(bsdf, base_color, metallic, specular, specular_tint, roughness):
    _set(bsdf.inputs["Base Color"], tuple(float(c) for c in base_color) + (1.0,))
    _set(bsdf.inputs["Metallic"], float(metallic))
    _set(bsdf.inputs["Specular"], float(specular))
    _set(bsdf.inputs["Specular Tint"], float(specular_tint))
    _set(bsdf.inputs["Roughness"], float(roughness))


def make_lambert_material(name):
    """A material whose output's Surface is a Diffuse BSDF of roughness 0 (Lambert; > 0 is Oren-Nayar)."""
    mat, bsdf = _material_with(name, "ShaderNodeBsdfDiffuse")
    bsdf.inputs["Roughness"].default_value = 0.0
    return mat, bsdf


def make_glossy_material(name, distribution):
    """A Glossy BSDF (no Fresnel: colour D G / (4 cos cos), alpha = Roughness^2)."""
    mat, bsdf = _material_with(name, "ShaderNodeBsdfGlossy")
    bsdf.distribution = distribution
    return mat, bsdf


def set_color(socket, rgb):
    _set(socket, tuple(float(c) for c in rgb) + (1.0,))


def _set(socket, value):
    if isinstance(value, tuple):
        if tuple(socket.default_value) != value:
            socket.default_value = value
    elif socket.default_value != value:
        socket.default_value = value


def _material_with(name, bsdf_type):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new(bsdf_type)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat, bsdf


def configure_render(scene, size, samples, seed, threads, film_transparent):
    """Cycles on the CPU, direct light only, every pixel exactly `samples` samples, box filter of one pixel,
    Standard view transform, no compositing; `film_transparent` makes alpha the coverage."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_percentage = 100
    r.pixel_aspect_x = 1.0
    r.pixel_aspect_y = 1.0
    r.use_border = False
    r.film_transparent = film_transparent
    r.use_file_extension = False
    r.dither_intensity = 0.0
    vs = scene.view_settings
    vs.view_transform = "Standard"
    vs.look = "None"
    vs.exposure = 0.0
    vs.gamma = 1.0
    vs.use_curve_mapping = False

    c = scene.cycles
    c.device = "CPU"
    c.feature_set = "SUPPORTED"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_animated_seed = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0  # box over exactly one pixel
    c.blur_glossy = 0.0
    c.caustics_reflective = False
    c.caustics_refractive = False
    c.film_exposure = 1.0
    # Direct light only: bounces count the indirect ones, so 0 still gives the light at the
    # first hit (a convex sphere under a black world has no indirect light anyway).
    c.max_bounces = 0
    c.diffuse_bounces = 0
    c.glossy_bounces = 0
    c.transmission_bounces = 0
    c.volume_bounces = 0
    c.transparent_max_bounces = 0
    if hasattr(c, "use_guiding"):
        c.use_guiding = False

    scene.view_layers[0].use_pass_combined = True
    scene.use_nodes = False
    r.use_compositing = False
    set_sampling(scene, size, samples, seed, threads)


def set_sampling(scene, size, samples, seed, threads):
    """Image size (square), samples per pixel, fixed seed, and CPU threads (0: automatic)."""
    r = scene.render
    if r.resolution_x != size or r.resolution_y != size:
        r.resolution_x = size
        r.resolution_y = size
    c = scene.cycles
    if c.samples != samples:
        c.samples = samples
    if c.seed != seed:
        c.seed = seed
    mode = "FIXED" if threads > 0 else "AUTO"
    if r.threads_mode != mode:
        r.threads_mode = mode
    if threads > 0 and r.threads != threads:
        r.threads = threads
