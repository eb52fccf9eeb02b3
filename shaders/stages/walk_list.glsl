// The depth test's walk list (src/render/stages/walk_list.rs), which both masks' first passes
// append to and their second passes (WALKS_FROM_LIST, which only read it) walk from: the
// second pass's indirect dispatch (x, y, z), x the groups of WALK_GROUP pixels up to
// MAX_GROUPS, then the list's length, set to (0, 1, 1, 0) before the first pass
// (src/render/passes.rs); and the pixels left to walk from (their indices in Masked).
//
// The includer defines, before including this file, WALK_ARGS_BINDING and WALK_PIXELS_BINDING
// (the two buffers' bindings) and WALK_MAX_GROUPS_ID (MAX_GROUPS's specialization constant).
#ifdef WALKS_FROM_LIST
#define WALK_LIST_ACCESS readonly
#else
#define WALK_LIST_ACCESS
#endif
layout(set = 0, binding = WALK_ARGS_BINDING, std430) WALK_LIST_ACCESS buffer WalkArgs { uvec4 walk_args; };
layout(set = 0, binding = WALK_PIXELS_BINDING, std430) WALK_LIST_ACCESS buffer WalkPixels { uint walk_pixels[]; };

// The most workgroups the second pass's indirect dispatch holds (its groups stride over a
// longer list).
layout(constant_id = WALK_MAX_GROUPS_ID) const uint MAX_GROUPS = 1u;
// Pixels a workgroup of the second pass takes in a round: its 8 x 8 invocations.
const uint WALK_GROUP = 64u;

#ifdef WALKS_FROM_LIST
// The entry of the list this invocation of the second pass takes first...
uint first_listed() {
    return gl_WorkGroupID.x * WALK_GROUP + gl_LocalInvocationIndex;
}

// ...and how far on it takes the next.
uint listed_stride() {
    return gl_NumWorkGroups.x * WALK_GROUP;
}
#else
// Lists pixel `index` for the second pass, and counts the workgroups it takes.
void list_walk(uint index) {
    uint at = atomicAdd(walk_args.w, 1u);
    walk_pixels[at] = index;
    if (at % WALK_GROUP == 0u && at / WALK_GROUP < MAX_GROUPS) {
        atomicAdd(walk_args.x, 1u);
    }
}
#endif
