"""The material that renders a volstyle volume in Cycles and EEVEE as volstyle does (SPEC §1):

    σt = extinction (`density`, or RGB `extinction`)   σs = albedo · σt   σa = σt − σs
    emission enters as σt · `emission`

built from Volume Scatter (σs), Volume Absorption (σa: Blender absorbs (1 − colour) · density) and
Emission (σt · emission), each RGB coefficient split into a colour in [0, 1] and a strength (its
largest channel), because EEVEE clamps shader colours to [0, 1] where Cycles does not. A grid the
volume lacks takes volstyle's default: albedo 1, emission 0. docs/CLIENTS.md gives the recipe."""
from __future__ import annotations

import bpy


def _attribute(nodes, name: str, x: float, y: float):
    a = nodes.new("ShaderNodeAttribute")
    a.attribute_name = name
    a.location = (x, y)
    return a


def _math(nodes, links, operation: str, a, b, x: float, y: float):
    m = nodes.new("ShaderNodeVectorMath")
    m.operation = operation
    m.location = (x, y)
    for socket, value in ((m.inputs[0], a), (m.inputs[1], b)):
        if isinstance(value, (tuple, list)):
            socket.default_value = value
        else:
            links.new(value, socket)
    return m


def _split(nodes, links, rgb, x: float, y: float):
    """An RGB coefficient as (colour in [0, 1], strength): strength = its largest channel."""
    sep = nodes.new("ShaderNodeSeparateXYZ")
    sep.location = (x, y)
    links.new(rgb, sep.inputs[0])
    m1 = nodes.new("ShaderNodeMath")
    m1.operation, m1.location = "MAXIMUM", (x + 150, y)
    links.new(sep.outputs[0], m1.inputs[0])
    links.new(sep.outputs[1], m1.inputs[1])
    m2 = nodes.new("ShaderNodeMath")
    m2.operation, m2.location = "MAXIMUM", (x + 300, y)
    links.new(m1.outputs[0], m2.inputs[0])
    links.new(sep.outputs[2], m2.inputs[1])
    safe = nodes.new("ShaderNodeMath")  # no division by zero where the coefficient is 0
    safe.operation, safe.location = "MAXIMUM", (x + 450, y - 80)
    links.new(m2.outputs[0], safe.inputs[0])
    safe.inputs[1].default_value = 1e-20
    colour = _math(nodes, links, "DIVIDE", rgb, safe.outputs[0], x + 600, y).outputs["Vector"]
    return colour, m2.outputs[0]


def volume_material(name: str, grids: dict, anisotropy: float = 0.0, emission: bool = True, scattering: bool = True):
    """A material for a volume holding `grids` ({name: Blender data_type}, as the file has them:
    extinction is a float `density` or `extinction`, or a vector `extinction`). `emission` or
    `scattering` off leave that part out (to compare them apart, docs/CLIENTS.md)."""
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    out.location = (1050, 0)
    extinction = "extinction" if "extinction" in grids else "density"
    sigma_t = _attribute(nodes, extinction, -600, 200).outputs["Fac" if grids.get(extinction) == "FLOAT" else "Vector"]
    if "albedo" in grids:
        albedo = _attribute(nodes, "albedo", -600, 0).outputs["Vector"]
    else:
        albedo = (1.0, 1.0, 1.0)
    sigma_s = _math(nodes, links, "MULTIPLY", sigma_t, albedo, -350, 150).outputs["Vector"]
    sigma_a = _math(nodes, links, "SUBTRACT", sigma_t, sigma_s, -350, -50).outputs["Vector"]
    if not scattering:  # no scattering: all of σt absorbs
        sigma_a = _math(nodes, links, "MULTIPLY", sigma_t, (1.0, 1.0, 1.0), -350, -50).outputs["Vector"]

    shaders = []
    if scattering:
        colour, strength = _split(nodes, links, sigma_s, -200, 400)
        scatter = nodes.new("ShaderNodeVolumeScatter")
        scatter.location = (650, 300)
        scatter.inputs["Anisotropy"].default_value = anisotropy
        links.new(colour, scatter.inputs["Color"])
        links.new(strength, scatter.inputs["Density"])
        shaders.append(scatter.outputs[0])
    colour, strength = _split(nodes, links, sigma_a, -200, 100)
    absorb_colour = _math(nodes, links, "SUBTRACT", (1.0, 1.0, 1.0), colour, 500, 100).outputs["Vector"]
    absorption = nodes.new("ShaderNodeVolumeAbsorption")
    absorption.location = (650, 50)
    links.new(absorb_colour, absorption.inputs["Color"])
    links.new(strength, absorption.inputs["Density"])
    shaders.append(absorption.outputs[0])
    if emission and "emission" in grids:
        radiance = _math(nodes, links, "MULTIPLY", sigma_t, _attribute(nodes, "emission", -600, -250).outputs["Vector"], -350, -250)
        colour, strength = _split(nodes, links, radiance.outputs["Vector"], -200, -250)
        emit = nodes.new("ShaderNodeEmission")
        emit.location = (650, -200)
        links.new(colour, emit.inputs["Color"])
        links.new(strength, emit.inputs["Strength"])
        shaders.append(emit.outputs[0])
    total = shaders[0]
    for k, s in enumerate(shaders[1:]):
        add = nodes.new("ShaderNodeAddShader")
        add.location = (850, 150 - 150 * k)
        links.new(total, add.inputs[0])
        links.new(s, add.inputs[1])
        total = add.outputs[0]
    links.new(total, out.inputs["Volume"])
    return mat
