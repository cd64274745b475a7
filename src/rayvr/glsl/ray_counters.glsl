// Rays traced per view (rayvr/rendergraph/ray_counters.py): a ray pass compiled with RQ_COUNT_RAYS 1
// (its class says COUNTS_RAYS) ends each kernel with ray_count_commit(layer): the queries the
// invocation began (ray_query.glsl rq_rays) go to the counter of its view. With the subgroup
// extensions a subgroup whose lanes share one view adds one sum, so a frame costs an image atomic
// per subgroup instead of one per pixel; lanes of several views add their own counts. Each
// view has RAY_COUNT_SLOTS counters (the image's rows), a workgroup adding to the one its index
// picks, because atomics on one address serialise and a frame makes ~10^5 of them; the host sums
// the rows.
#pragma once
#include "ray_query.glsl"

#if defined(RQ_COUNT_RAYS) && RQ_COUNT_RAYS
layout(r32ui, binding = RAYVR_RAY_COUNTER_IMAGE) uniform uimage2D rayvr_ray_counts;

// The counter row of this workgroup: its index over the dispatch, spread over the rows.
int ray_count_slot() {
    uvec3 g = gl_WorkGroupID, n = gl_NumWorkGroups;
    return int((g.x + n.x * (g.y + n.y * g.z)) % uint(RAY_COUNT_SLOTS));
}

void ray_count_commit(uint view) {
    uint n = rq_rays;
    rq_rays = 0u;
#if defined(GL_KHR_shader_subgroup_arithmetic) && defined(GL_KHR_shader_subgroup_vote)
    if (subgroupAllEqual(view)) {   // one view (the common case): one sum, one atomic
        uint sum = subgroupAdd(n);
        if (subgroupElect() && sum > 0u) imageAtomicAdd(rayvr_ray_counts, ivec2(int(view), ray_count_slot()), sum);
        return;
    }
#endif
    // lanes of several views (camera grids): an atomic per lane in one instruction, where a loop over
    // the views would cost a reduction each
    if (n > 0u) imageAtomicAdd(rayvr_ray_counts, ivec2(int(view), ray_count_slot()), n);
}
#else
void ray_count_commit(uint view) {}
#endif
