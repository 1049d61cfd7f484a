"""The material that renders a volstyle volume in Cycles and EEVEE as volstyle does (SPEC §1):

    σt = extinction (`density`, or RGB `extinction`)   σs = albedo · σt   σa = σt − σs
    emission enters as σt · `emission`

built from Volume Scatter (colour σs, density 1, anisotropy g), Volume Absorption (colour 1 − σa,
density 1: Cycles absorbs (1 − colour) · density) and Emission (colour σt · emission). A grid the
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


def volume_material(name: str, grids: dict, anisotropy: float = 0.0, emission: bool = True, scattering: bool = True):
    """A material for a volume holding `grids` ({name: Blender data_type}, as the file has them:
    extinction is a float `density` or `extinction`, or a vector `extinction`). `emission` or
    `scattering` off leave that part out (to compare them apart, docs/CLIENTS.md)."""
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    out.location = (900, 0)
    extinction = "extinction" if "extinction" in grids else "density"
    sigma_t = _attribute(nodes, extinction, -600, 200).outputs["Fac" if grids.get(extinction) == "FLOAT" else "Vector"]
    if "albedo" in grids:
        albedo = _attribute(nodes, "albedo", -600, 0).outputs["Vector"]
    else:
        albedo = (1.0, 1.0, 1.0)
    sigma_s = _math(nodes, links, "MULTIPLY", sigma_t, albedo, -350, 150).outputs["Vector"]
    sigma_a = _math(nodes, links, "SUBTRACT", sigma_t, sigma_s, -150, 0).outputs["Vector"]
    absorb_colour = _math(nodes, links, "SUBTRACT", (1.0, 1.0, 1.0), sigma_a, 50, 0).outputs["Vector"]

    shaders = []
    scatter = nodes.new("ShaderNodeVolumeScatter")
    scatter.location = (300, 250)
    scatter.inputs["Density"].default_value = 1.0
    scatter.inputs["Anisotropy"].default_value = anisotropy
    links.new(sigma_s, scatter.inputs["Color"])
    absorption = nodes.new("ShaderNodeVolumeAbsorption")
    absorption.location = (300, 50)
    absorption.inputs["Density"].default_value = 1.0
    links.new(absorb_colour, absorption.inputs["Color"])
    if scattering:
        shaders += [scatter.outputs[0], absorption.outputs[0]]
    else:  # no scattering: all of σt absorbs
        all_absorbed = _math(nodes, links, "SUBTRACT", (1.0, 1.0, 1.0), sigma_t, 50, -150).outputs["Vector"]
        links.new(all_absorbed, absorption.inputs["Color"])
        shaders.append(absorption.outputs[0])
    if emission and "emission" in grids:
        radiance = _math(nodes, links, "MULTIPLY", sigma_t, _attribute(nodes, "emission", -600, -250).outputs["Vector"], -150, -250)
        emit = nodes.new("ShaderNodeEmission")
        emit.location = (300, -200)
        emit.inputs["Strength"].default_value = 1.0
        links.new(radiance.outputs["Vector"], emit.inputs["Color"])
        shaders.append(emit.outputs[0])
    total = shaders[0]
    for k, s in enumerate(shaders[1:]):
        add = nodes.new("ShaderNodeAddShader")
        add.location = (550, 150 - 150 * k)
        links.new(total, add.inputs[0])
        links.new(s, add.inputs[1])
        total = add.outputs[0]
    links.new(total, out.inputs["Volume"])
    return mat
