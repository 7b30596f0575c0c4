// A vertex of a geometry pass placed by its instance (render.mesh.GpuMesh): every geometry
// program's vertex stage reads the mesh's vertex (position, normal, part) and its instance's
// rows of the affine transform, rows of the normals' transform, part and first face, so a
// mesh used N times is uploaded once. A flattened model is one instance of the identity, whose
// products give its vertices to the bit.
in vec3 in_position;
in vec3 in_normal;
in int in_part;
in vec4 i_x;
in vec4 i_y;
in vec4 i_z;
in vec3 i_nx;
in vec3 i_ny;
in vec3 i_nz;
in int i_part;
in int i_face;

// the vertex in the scene's coordinates
vec3 placed_position() {
    vec4 p = vec4(in_position, 1.0);
    return vec3(dot(i_x, p), dot(i_y, p), dot(i_z, p));
}

// its normal in the scene's coordinates (zero where the mesh has none)
vec3 placed_normal() {
    return vec3(dot(i_nx, in_normal), dot(i_ny, in_normal), dot(i_nz, in_normal));
}

// its part: the vertex's own within a flattened block, plus the instance's
int placed_part() {
    return in_part + i_part;
}
