// geometric.wgsl: the shading point's geometric data and the stdlib geometric nodes.
//
// `mx_geometry` is filled by the compiler's kernel glue and passed as the first parameter
// (`geom`) of every function that reads geometry (README rule 4). Field order is fixed.
//
// Nodes: position, normal, tangent, bitangent (vector3; `space` enum model,object,world → 0,1,2,
// "model" is an alias of "object", as in MaterialX's GLSL generator), texcoord (vector2,
// vector3; only UV set 0 exists, so `index` is ignored).
//
// Not functions here: geomcolor_* and geompropvalue_* read named geometry streams, which the
// compiler makes interface inputs of the kernel (`geomcolor<index>`, and the `geomprop` name,
// defaulting to the node's `default`): per-point columns the caller supplies. frame and time are
// interface inputs `time` and `frame` likewise (compiler/src/graph_builder.rs,
// APPLICATION_INPUTS). geompropvalueuniform_string/filename (compile-time values uplift is not
// given) are refused at the node; bump is a nodegraph.

struct mx_geometry {
    texcoord: vec2<f32>,
    position_object: vec3<f32>,
    position_world: vec3<f32>,
    normal_object: vec3<f32>,
    normal_world: vec3<f32>,
    tangent_object: vec3<f32>,
    tangent_world: vec3<f32>,
    bitangent_object: vec3<f32>,
    bitangent_world: vec3<f32>,
}

// normalize() that maps a zero vector to zero instead of NaN (MaterialX's GLSL would produce
// NaN for a degenerate stream; a missing tangent stream is the usual cause).
fn mx_geometry_safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    if (len2 > 0.0) {
        return v * inverseSqrt(len2);
    }
    return vec3<f32>(0.0);
}

// ND_position_vector3: space (model=0, object=1, world=2; default object).
fn mx_position_vector3(geom: mx_geometry, space: i32) -> vec3<f32> {
    if (space == 2) {
        return geom.position_world;
    }
    return geom.position_object;
}

// ND_normal_vector3: normalized normal in the requested space.
fn mx_normal_vector3(geom: mx_geometry, space: i32) -> vec3<f32> {
    if (space == 2) {
        return mx_geometry_safe_normalize(geom.normal_world);
    }
    return mx_geometry_safe_normalize(geom.normal_object);
}

// ND_tangent_vector3: normalized tangent; `index` selects a UV set, only set 0 exists.
fn mx_tangent_vector3(geom: mx_geometry, space: i32, index: i32) -> vec3<f32> {
    if (space == 2) {
        return mx_geometry_safe_normalize(geom.tangent_world);
    }
    return mx_geometry_safe_normalize(geom.tangent_object);
}

// ND_bitangent_vector3: normalized bitangent; `index` selects a UV set, only set 0 exists.
fn mx_bitangent_vector3(geom: mx_geometry, space: i32, index: i32) -> vec3<f32> {
    if (space == 2) {
        return mx_geometry_safe_normalize(geom.bitangent_world);
    }
    return mx_geometry_safe_normalize(geom.bitangent_object);
}

// ND_texcoord_vector2: UV set `index`; only set 0 exists, any index returns it.
fn mx_texcoord_vector2(geom: mx_geometry, index: i32) -> vec2<f32> {
    return geom.texcoord;
}

// ND_texcoord_vector3: (u, v, 0).
fn mx_texcoord_vector3(geom: mx_geometry, index: i32) -> vec3<f32> {
    return vec3<f32>(geom.texcoord, 0.0);
}
