// The workgroup shape of the ray passes' image-wide dispatches: RAY_GROUP_X x RAY_GROUP_Y pixels
// in each of RAY_GROUP_Z consecutive views (rayvr.passes._common.ray_group), views innermost, so a
// warp holds the same few pixels of several neighbouring views: in a camera grid those rays are
// nearly parallel and hit nearly the same surfaces. The dispatch is (pixels / X, pixels / Y,
// views / Z) workgroups of RAY_GROUP_SIZE invocations (the shader declares its local size: an
// #include is expanded even inside a false #if, so this file declares no layout). With
// RAY_GROUP_Z 1 this is the usual X x Y tile of one view. With RAY_GROUP_VIEW_ORDER (a uint array of
// RAY_GROUP_VIEWS entries: passes.dispatch.view_order) the workgroups take the views in that order.
// With RAY_GROUP_COMPACT (one view; passes.dispatch.decision_group) the workgroup is made of
// RAY_GROUP_WARP_X x RAY_GROUP_WARP_Y tiles, one a warp, and ray_group_compact gives the pixels
// that have work the first lanes, so a few traced pixels of the workgroup fill one warp.
#pragma once
#ifdef RAY_GROUP_Z

#define RAY_GROUP_SIZE (RAY_GROUP_X * RAY_GROUP_Y * RAY_GROUP_Z)

// The (x, y, view) of invocation `lane` of workgroup `group`; may lie past the image or the last
// view: callers bound it.
ivec3 ray_group_pixel_of(uvec3 group, uint lane) {
    uint tile = lane / uint(RAY_GROUP_Z);
#if RAY_GROUP_COMPACT
    const uint warp = uint(RAY_GROUP_WARP_X * RAY_GROUP_WARP_Y), tiles_x = uint(RAY_GROUP_X / RAY_GROUP_WARP_X);
    uint w = tile / warp, i = tile % warp;
    uvec3 local = uvec3(uvec2(w % tiles_x, w / tiles_x) * uvec2(RAY_GROUP_WARP_X, RAY_GROUP_WARP_Y)
                        + uvec2(i % uint(RAY_GROUP_WARP_X), i / uint(RAY_GROUP_WARP_X)), 0u);
#else
    uvec3 local = uvec3(tile % uint(RAY_GROUP_X), tile / uint(RAY_GROUP_X), lane % uint(RAY_GROUP_Z));
#endif
    ivec3 p = ivec3(group * uvec3(RAY_GROUP_X, RAY_GROUP_Y, RAY_GROUP_Z) + local);
#ifdef RAY_GROUP_VIEW_ORDER
    const uint order[RAY_GROUP_VIEWS] = RAY_GROUP_VIEW_ORDER;
    if (p.z < RAY_GROUP_VIEWS) p.z = int(order[p.z]);
#endif
    return p;
}

// This invocation's (x, y, view).
ivec3 ray_group_pixel() { return ray_group_pixel_of(gl_WorkGroupID, gl_LocalInvocationIndex); }

#if RAY_GROUP_COMPACT
shared uint ray_group_count;
shared uint ray_group_lanes[RAY_GROUP_SIZE];

// Every invocation of the workgroup calls it, in uniform control flow (it holds barriers): `work`
// says whether this invocation's own pixel has work. The invocations with work hand their lanes to
// the first invocations (in the shared atomic's order: each pixel's work is its own, so the order
// changes no result); one of those gets its pixel in p and true, every other invocation false.
bool ray_group_compact(bool work, inout ivec3 p) {
    if (gl_LocalInvocationIndex == 0u) ray_group_count = 0u;
    memoryBarrierShared();
    barrier();
    if (work) ray_group_lanes[atomicAdd(ray_group_count, 1u)] = gl_LocalInvocationIndex;
    memoryBarrierShared();
    barrier();
    if (gl_LocalInvocationIndex >= ray_group_count) return false;
    p = ray_group_pixel_of(gl_WorkGroupID, ray_group_lanes[gl_LocalInvocationIndex]);
    return true;
}
#endif
#endif
