// The workgroup shape of the ray passes' image-wide dispatches: RAY_GROUP_X x RAY_GROUP_Y pixels
// in each of RAY_GROUP_Z consecutive views (rayvr.passes._common.ray_group), views innermost, so a
// warp holds the same few pixels of several neighbouring views: in a camera grid those rays are
// nearly parallel and hit nearly the same surfaces. The dispatch is (pixels / X, pixels / Y,
// views / Z) workgroups of RAY_GROUP_SIZE invocations (the shader declares its local size: an
// #include is expanded even inside a false #if, so this file declares no layout). With
// RAY_GROUP_Z 1 this is the usual X x Y tile of one view. With RAY_GROUP_VIEW_ORDER (a uint array of
// RAY_GROUP_VIEWS entries: passes.dispatch.view_order) the workgroups take the views in that order.
// With WORK_TILES_INPUT (glsl/work_tiles.glsl) the workgroups are the listed tiles.
#pragma once
#include "work_tiles.glsl"
#ifdef RAY_GROUP_Z

#define RAY_GROUP_SIZE (RAY_GROUP_X * RAY_GROUP_Y * RAY_GROUP_Z)

// The (x, y, view) of invocation `lane` of workgroup `group`; may lie past the image or the last
// view: callers bound it.
ivec3 ray_group_pixel_of(uvec3 group, uint lane) {
    uint tile = lane / uint(RAY_GROUP_Z);
    uvec3 local = uvec3(tile % uint(RAY_GROUP_X), tile / uint(RAY_GROUP_X), lane % uint(RAY_GROUP_Z));
    ivec3 p = ivec3(group * uvec3(RAY_GROUP_X, RAY_GROUP_Y, RAY_GROUP_Z) + local);
#ifdef RAY_GROUP_VIEW_ORDER
    const uint order[RAY_GROUP_VIEWS] = RAY_GROUP_VIEW_ORDER;
    if (p.z < RAY_GROUP_VIEWS) p.z = int(order[p.z]);
#endif
    return p;
}

// This invocation's (x, y, view); with WORK_TILES_INPUT its workgroup's tile is the list's.
ivec3 ray_group_pixel() {
#if WORK_TILES_INPUT
    return ray_group_pixel_of(work_tile(), gl_LocalInvocationIndex);
#else
    return ray_group_pixel_of(gl_WorkGroupID, gl_LocalInvocationIndex);
#endif
}
#endif
