// Push constants of one draw (one posed mesh in one view); must match render::draw::DrawConstants.
layout(push_constant, std430) uniform Draw {
    mat4 clip_from_model;   // view grid ∘ view rotation ∘ pose, composed in f64 on the host
    vec4 view_z_row;        // the row of view_from_model that gives the view-frame z
    uvec2 surface_ids;      // device address of the mesh's per-triangle surface ids
    uint label_base;        // label = label_base + surface id
} draw;
