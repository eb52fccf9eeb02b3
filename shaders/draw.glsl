// Push constants of one draw (one posed mesh in one view); must match render::draw::DrawConstants.
layout(push_constant, std430) uniform Draw {
    vec4 view_from_model[3]; // rows of view rotation ∘ pose, composed in f64 on the host
    vec4 grid;               // x0, y0, dx, dy: the view's pixel (0, 0) centre and pitch
    vec2 size;               // width, height in pixels
    vec2 z_range;            // z_min, z_max mapped onto depth 1..0 (larger z is closer)
    uvec2 positions;         // device addresses of the mesh's packed xyz positions,
    uvec2 indices;           // its triangle indices,
    uvec2 surface_ids;       // its per-triangle surface ids,
    uvec2 normals;           // and its per-triangle unit normals (model frame, f64-derived)
    uint label_base;         // label = label_base + surface id
} draw;

vec3 to_view(vec3 model) {
    vec4 p = vec4(model, 1.0);
    return vec3(dot(draw.view_from_model[0], p), dot(draw.view_from_model[1], p), dot(draw.view_from_model[2], p));
}

// The rotation part alone: directions (normals) do not translate.
vec3 rotate_to_view(vec3 direction) {
    return vec3(dot(draw.view_from_model[0].xyz, direction), dot(draw.view_from_model[1].xyz, direction),
                dot(draw.view_from_model[2].xyz, direction));
}
