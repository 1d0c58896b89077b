// The run's colliders (/colliders: shape, dimensions in its own frame with axis z, rest pose; a
// mesh collider's surface) as translucent objects, posed at each frame as the run recorded them
// (a point l of the shape's frame at A l + b; a band's radius times its scale), and the skeleton's
// bones (/bones: a capsule in the rest pose) as solid capsules, drawn through the tissue.

function shapeGeometry(THREE, c, size) {
  const d = c.dimensions;
  switch (c.shape) {
    case "sphere": return new THREE.SphereGeometry(d.radius, 32, 16);
    case "capsule": return new THREE.CapsuleGeometry(d.radius, d.length, 8, 24).rotateX(Math.PI / 2);
    case "cylinder": return new THREE.CylinderGeometry(d.radius, d.radius, d.length, 32, 1, true).rotateX(Math.PI / 2);
    case "box": return new THREE.BoxGeometry(d.size_x, d.size_y, d.size_z);
    case "plane": return new THREE.PlaneGeometry(size, size);
    case "mesh": {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(new Float32Array(c.vertices), 3));
      g.setIndex(c.triangles);
      g.computeVertexNormals();
      return g;
    }
    default: return null;
  }
}

export function colliderObject(THREE, c, radius) {
  const geometry = shapeGeometry(THREE, c, 6 * radius);
  if (!geometry) return null;
  const ground = c.shape === "plane";
  const material = new THREE.MeshStandardMaterial({ color: ground ? 0xb9b9b0 : 0x8fa3b8, transparent: true, opacity: ground ? 0.55 : 0.35, side: THREE.DoubleSide, depthWrite: false });
  const o = new THREE.Mesh(geometry, material);
  o.matrixAutoUpdate = false;
  o.userData.shape = c.shape;
  return o;
}

// Pose (12: A row-major, then b) and the radius factor of a band (scales x and y, the axis is z).
export function poseCollider(o, c, pose, scale) {
  const m = o.matrix;
  m.set(pose[0], pose[1], pose[2], pose[9], pose[3], pose[4], pose[5], pose[10], pose[6], pose[7], pose[8], pose[11], 0, 0, 0, 1);
  if (scale !== 1 && (c.shape === "cylinder" || c.shape === "capsule" || c.shape === "sphere")) {
    const s = new o.matrix.constructor().makeScale(scale, scale, c.shape === "sphere" ? scale : 1);
    m.multiply(s);
  }
  o.matrixWorldNeedsUpdate = true;
}

// A bone's capsule, built where it lies in the rest pose (world coordinates), so that its pose
// (A, b: a rest point X at A X + b) is its matrix. A bone with no capsule shows as a small sphere.
export function boneObject(THREE, bone, radius) {
  const from = new THREE.Vector3(...bone.from), to = new THREE.Vector3(...bone.to);
  const r = Math.max(bone.radius, 0.01 * radius);
  const length = from.distanceTo(to);
  const geometry = length > 0 ? new THREE.CapsuleGeometry(r, length, 6, 16) : new THREE.SphereGeometry(r, 16, 8);
  if (length > 0) {
    const along = new THREE.Quaternion().setFromUnitVectors(new THREE.Vector3(0, 1, 0), to.clone().sub(from).normalize());
    geometry.applyQuaternion(along);
  }
  geometry.translate(...from.clone().add(to).multiplyScalar(0.5).toArray());
  const o = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: 0xe8dcc0, depthTest: false, transparent: true, opacity: 0.85 }));
  o.renderOrder = 2;
  o.matrixAutoUpdate = false;
  return o;
}

export function poseBone(o, pose) {
  o.matrix.set(pose[0], pose[1], pose[2], pose[9], pose[3], pose[4], pose[5], pose[10], pose[6], pose[7], pose[8], pose[11], 0, 0, 0, 1);
  o.matrixWorldNeedsUpdate = true;
}
