"""The BVH4 collapse (rayvr.scene.bvh_wide): every slot reached once, exact child boxes ("bvh4")
or quantised ones that hold every triangle as the shader decodes them ("bvh4q"), at most 4
children, empty slots no ray enters, and the links GpuScene offsets."""
import dataclasses

import numpy as np
import pytest
import trimesh

from rayvr.scene import bvh_layouts, bvh_wide
from rayvr.scene.bvh import build, triangle_bounds

LEAF, MASK = int(bvh_wide.LEAF_BIT), int(bvh_wide.LINK_MASK)


def walk(w, prim_lo, prim_hi):
    """From the root: per leaf slot how often it is reached, per node how often it is visited,
    and each child's (lo, hi) as the GPU reads it next to its subtree's primitive bounds (slot
    order). Asserts on the way that every primitive lies inside every box on its path."""
    lo, hi = w.child_boxes()
    items = w.nodes.view(np.uint32)[:, -4:]
    reached = np.zeros(len(w.order), np.int64)
    visited = np.zeros(w.node_count, np.int64)
    pairs = []

    def subtree(node, path_lo, path_hi):
        visited[node] += 1
        box_lo, box_hi = np.full(3, np.inf, np.float32), np.full(3, -np.inf, np.float32)
        children = 0
        for c in range(4):
            item = int(items[node, c])
            if w.slots[node, c] < 0:
                assert item == 0
                continue
            children += 1
            c_lo, c_hi = np.maximum(path_lo, lo[node, c]), np.minimum(path_hi, hi[node, c])
            if item & LEAF:
                first, count = item & MASK, ((item >> 28) & 7) + 1
                reached[first:first + count] += 1
                p_lo, p_hi = prim_lo[first:first + count], prim_hi[first:first + count]
                assert (p_lo >= c_lo).all() and (p_hi <= c_hi).all(), (node, c)
                s_lo, s_hi = p_lo.min(0), p_hi.max(0)
            else:
                s_lo, s_hi = subtree(item, c_lo, c_hi)
            pairs.append((lo[node, c], hi[node, c], s_lo, s_hi))
            box_lo, box_hi = np.minimum(box_lo, s_lo), np.maximum(box_hi, s_hi)
        assert 1 <= children <= 4
        return box_lo, box_hi

    subtree(0, np.full(3, -np.inf, np.float32), np.full(3, np.inf, np.float32))
    return reached, visited, pairs


def check(w, lo, hi):
    reached, visited, pairs = walk(w, lo[w.order], hi[w.order])
    np.testing.assert_array_equal(reached, 1)      # every primitive in exactly one leaf
    np.testing.assert_array_equal(visited, 1)      # every node reachable, once
    for c_lo, c_hi, s_lo, s_hi in pairs:            # child boxes are exactly their subtree's bounds
        np.testing.assert_array_equal(c_lo, s_lo)
        np.testing.assert_array_equal(c_hi, s_hi)
    e_lo, e_hi, empty = w.exact_child_boxes()
    assert (e_lo[empty] == 1e30).all() and (e_hi[empty] == 1e30).all()   # empty slots: a box no ray reaches


def check_quantized(w, lo, hi):
    """Every primitive inside its decoded boxes from the root (walk), each decoded box at most one
    grid step looser than the exact one per side, and empty slots inverted with item 0."""
    q = dataclasses.replace(w, quantized=True)
    reached, visited, _ = walk(q, lo[q.order], hi[q.order])
    np.testing.assert_array_equal(reached, 1)
    np.testing.assert_array_equal(visited, 1)
    d_lo, d_hi = q.child_boxes()
    e_lo, e_hi, empty = q.exact_child_boxes()
    nodes = q.nodes
    scale = (((nodes.view(np.uint32)[:, 3:4] >> np.array([0, 8, 16], np.uint32)) & 0xFF) << 23).view(np.float32)
    step = scale[:, None, :] + np.spacing(np.abs(e_lo)) + np.spacing(np.abs(e_hi))
    live = ~empty
    assert (d_lo[live] <= e_lo[live]).all() and (d_hi[live] >= e_hi[live]).all()
    assert (e_lo - d_lo <= step)[live].all() and (d_hi - e_hi <= step)[live].all()
    # empty slots: item 0, which the traversal never enters, and an inverted box on every axis
    # where the node has extent (the slab test picking near/far planes by the ray's signs misses it)
    assert (nodes.view(np.uint32)[:, -4:][empty] == 0).all()
    origin = nodes[:, 0:3]
    top = np.where(live[..., None], e_hi, -np.inf).max(axis=1)
    inverted = d_lo > d_hi
    has_extent = np.broadcast_to((top > origin)[:, None, :], inverted.shape)
    assert inverted[empty & has_extent.any(-1)].any(-1).all()
    assert (inverted | ~has_extent)[empty].all()


@pytest.mark.parametrize("method", ["lbvh", "sah"])
def test_collapse_is_a_valid_bvh4(method):
    m = trimesh.creation.torus(1.0, 0.3, major_sections=32, minor_sections=16)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    b = build(lo, hi, method)
    w = bvh_wide.collapse(b)
    check(w, lo, hi)
    check_quantized(w, lo, hi)
    assert w.nodes.shape == (w.node_count, 28)
    assert bvh_wide.collapse(b, quantized=True).nodes.shape == (w.node_count, 16)
    assert (w.slots >= 0).sum(axis=1).mean() >= 3.0   # nodes are mostly full
    assert w.node_count < 0.45 * b.node_count


@pytest.mark.parametrize("n", [1, 3, 5, 9])
def test_collapse_of_tiny_trees(n):
    """A root whose whole mesh is one leaf (one child, three empty slots) and trees of a few leaves."""
    rng = np.random.default_rng(n)
    tris = rng.uniform(-1, 1, (n, 3, 3)).astype(np.float32)
    lo, hi = triangle_bounds(tris)
    w = bvh_wide.collapse(build(lo, hi, "sah", leaf_size=1 if n > 3 else 4))
    check(w, lo, hi)
    check_quantized(w, lo, hi)


def test_refit_of_the_source_shows_in_the_nodes():
    m = trimesh.creation.icosphere(subdivisions=2)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    b = build(lo, hi, "sah")
    w = bvh_wide.collapse(b)
    moved = (m.vertices * [2.0, 0.5, 1.0])[m.faces].astype(np.float32)
    b.refit(*triangle_bounds(moved))
    check(w, *triangle_bounds(moved))
    check_quantized(w, *triangle_bounds(moved))


@pytest.mark.parametrize("quantized", [False, True])
def test_relinked_offsets_nodes_and_maps_leaves(quantized):
    m = trimesh.creation.icosphere(subdivisions=2)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    w = bvh_wide.collapse(build(lo, hi, "sah"), quantized)
    items = w.nodes.view(np.uint32)[:, -4:]
    moved = w.relinked(lambda slot: slot + 1000, 7).view(np.uint32)
    np.testing.assert_array_equal(moved[:, :-4], w.nodes.view(np.uint32)[:, :-4])
    leaf, inner = (items & LEAF) != 0, ((items & LEAF) == 0) & (w.slots >= 0)
    np.testing.assert_array_equal(moved[:, -4:][leaf], items[leaf] + 1000)
    np.testing.assert_array_equal(moved[:, -4:][inner], items[inner] + 7)
    np.testing.assert_array_equal(moved[:, -4:][w.slots < 0], 0)


@pytest.mark.parametrize("offset", [0.0, 1e5, 1e6, -3e5])
@pytest.mark.parametrize("shape", ["torus", "flat", "tiny"])
def test_quantized_boxes_hold_their_triangles(offset, shape):
    """Far from the origin (float32 spacing 1/8 m at 1e6), flat along an axis (zero extent) and
    sub-ulp small: every triangle stays inside its decoded boxes."""
    m = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
    tris = m.triangles * {"torus": 1.0, "flat": [1.0, 1.0, 0.0], "tiny": 1e-6}[shape] + offset
    lo, hi = triangle_bounds(tris.astype(np.float32))
    check_quantized(bvh_wide.collapse(build(lo, hi, "sah")), lo, hi)


def test_quantized_nodes_are_64_bytes_of_a_shared_collapse():
    m = trimesh.creation.icosphere(subdivisions=3)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    b = build(lo, hi, "sah")
    w, q = bvh_wide.collapse(b), bvh_wide.collapse(b, quantized=True)
    np.testing.assert_array_equal(q.items, w.items)
    assert q.nbytes == w.node_count * 64 and w.nbytes == w.node_count * 112
    assert bvh_layouts.collapse_to(b, "bvh2") is b
