"""A binary glTF 2.0 (.glb) writer for the tools: one buffer, a buffer view per accessor, the JSON
and the binary chunk padded to 4 bytes as the specification asks. NumPy only (Debian 12 packages
no Python glTF library); the C++ reader (tinygltf) is the check that what it writes is valid."""
import json
import struct

import numpy as np

FLOAT, USHORT, UINT = 5126, 5123, 5125
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
_DTYPES = {FLOAT: "<f4", USHORT: "<u2", UINT: "<u4"}


class Glb:
    def __init__(self):
        self.bin = bytearray()
        self.gltf = {"asset": {"version": "2.0", "generator": "isochor"}, "scene": 0,
                     "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "accessors": [],
                     "bufferViews": [], "buffers": []}

    def accessor(self, values, component=FLOAT, per=None, bounds=False, target=None):
        """Appends values (an array whose last axis is the element, or flat with `per`) and
        returns the accessor's index; `bounds` writes min and max (POSITION needs them)."""
        a = np.asarray(values)
        per = per or (a.shape[-1] if a.ndim > 1 else 1)
        flat = np.ascontiguousarray(a.reshape(-1), dtype=_DTYPES[component])
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": flat.nbytes}
        if target is not None:
            view["target"] = target
        self.bin += flat.tobytes()
        self.gltf["bufferViews"].append(view)
        acc = {"bufferView": len(self.gltf["bufferViews"]) - 1, "componentType": component,
               "count": flat.size // per, "type": _TYPES[per]}
        if bounds:
            m = flat.reshape(-1, per).astype(float)
            acc["min"] = m.min(axis=0).tolist()
            acc["max"] = m.max(axis=0).tolist()
        self.gltf["accessors"].append(acc)
        return len(self.gltf["accessors"]) - 1

    def node(self, **fields):
        self.gltf["nodes"].append(fields)
        return len(self.gltf["nodes"]) - 1

    def mesh(self, primitive, **fields):
        self.gltf["meshes"].append(dict(primitives=[primitive], **fields))
        return len(self.gltf["meshes"]) - 1

    def triangles(self, tris):
        """The index accessor of a triangle list (uint16 where the vertices allow)."""
        tris = np.asarray(tris)
        component = USHORT if tris.max() < 65535 else UINT
        return self.accessor(tris.reshape(-1), component, per=1, target=34963)

    def to_bytes(self):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.gltf["buffers"] = [{"byteLength": len(self.bin)}]
        doc = {k: v for k, v in self.gltf.items() if v != []}
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        total = 12 + 8 + len(text) + 8 + len(self.bin)
        return (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(text), 0x4E4F534A) + text +
                struct.pack("<II", len(self.bin), 0x004E4942) + bytes(self.bin))
