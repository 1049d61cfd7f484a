"""Hostile mesh files of issue #35, made in memory (no file is committed for them)."""
import base64
import json
import struct

_TRIANGLE = struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0)


def _gltf(nodes, extra=None, buffer_bytes=None):
    doc = {
        'asset': {'version': '2.0'},
        'scene': 0,
        'scenes': [{'nodes': [0]}],
        'nodes': nodes,
        'meshes': [{'primitives': [{'attributes': {'POSITION': 0}}]}],
        'accessors': [{'bufferView': 0, 'componentType': 5126, 'count': 3, 'type': 'VEC3',
                       'min': [0, 0, 0], 'max': [1, 1, 0]}],
        'bufferViews': [{'buffer': 0, 'byteLength': 36}],
        'buffers': [{'byteLength': buffer_bytes or 36,
                     'uri': 'data:application/octet-stream;base64,' + base64.b64encode(_TRIANGLE).decode()}],
    }
    doc.update(extra or {})
    return doc


def gltf_triangle():
    return json.dumps(_gltf([{'mesh': 0}])).encode()


def gltf_chain(depth):
    """Nodes nested in one chain `depth` deep, the triangle at the bottom."""
    nodes = [{'children': [i + 1]} for i in range(depth - 1)] + [{'mesh': 0}]
    return json.dumps(_gltf(nodes)).encode()


def gltf_doubling(levels):
    """Every node references the next one twice: 2^levels copies once expanded (~1 KB)."""
    nodes = [{'children': [i + 1, i + 1]} for i in range(levels)] + [{'mesh': 0}]
    return json.dumps(_gltf(nodes), separators=(',', ':')).encode()


def gltf_cycle():
    return json.dumps(_gltf([{'children': [1]}, {'children': [0], 'mesh': 0}])).encode()


def gltf_deep_json(depth):
    doc = _gltf([{'mesh': 0}])
    text = json.dumps(doc)
    return (text[:-1] + ', "extras": ' + '[' * depth + ']' * depth + '}').encode()


def glb(doc, binary=b'', length=None):
    body = json.dumps(doc).encode()
    body += b' ' * (-len(body) % 4)
    chunks = struct.pack('<II', len(body), 0x4E4F534A) + body
    if binary:
        binary += b'\0' * (-len(binary) % 4)
        chunks += struct.pack('<II', len(binary), 0x004E4942) + binary
    total = 12 + len(chunks)
    return struct.pack('<4sII', b'glTF', 2, total if length is None else length) + chunks


def glb_triangle(**overrides):
    doc = _gltf([{'mesh': 0}])
    doc['buffers'] = [{'byteLength': overrides.pop('byte_length', 36)}]
    doc.update(overrides.pop('extra', {}))
    return glb(doc, _TRIANGLE, **overrides)


def ply(vertex_count, newline='\n', face_count=1):
    head = newline.join(['ply', 'format ascii 1.0', 'element vertex %s' % vertex_count, 'property float x',
                         'property float y', 'property float z', 'element face %s' % face_count,
                         'property list uchar int vertex_indices', 'end_header', ''])
    return (head + newline.join(['0 0 0', '1 0 0', '0 1 0', '3 0 1 2', ''])).encode()
