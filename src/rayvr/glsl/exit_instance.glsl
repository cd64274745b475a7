// An exit instance (SurfacePoint.exit_instance: what rays leaving a surface on its geometric
// normal's side may skip) and its form in a float channel, where the G-buffer's normW.w and a
// probe ray record's direct.a carry it: the instance + 1, 0 for none, exact below 2^24 instances
// (an instance beyond stores none: nothing skipped, never a wrong skip).
#pragma once

#define SCENE_NO_INSTANCE 0xFFFFFFFFu

float exit_instance_pack(uint exit_instance) { return exit_instance < 0xFFFFFFu ? float(exit_instance + 1u) : 0.0; }
uint exit_instance_unpack(float w) { return w >= 1.0 ? uint(w) - 1u : SCENE_NO_INSTANCE; }
