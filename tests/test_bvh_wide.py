"""The BVH4 collapse (rayvr.scene.bvh_wide): every slot reached once, exact child boxes, at most
4 children, empty slots no ray enters, and the links GpuScene offsets."""
import numpy as np
import pytest
import trimesh

from rayvr.scene import bvh_wide
from rayvr.scene.bvh import build, triangle_bounds

LEAF, MASK = int(bvh_wide.LEAF_BIT), int(bvh_wide.LINK_MASK)


def walk(w):
    """Per leaf slot how often it is reached, and each child's (lo, hi) next to its subtree's
    primitive bounds (slot order), from the root."""
    lo, hi = w.child_boxes()
    items = w.nodes.view(np.uint32)[:, 24:28]
    reached = np.zeros(len(w.order), np.int64)
    visited = np.zeros(w.node_count, np.int64)
    pairs = []

    def subtree(node, prim_lo, prim_hi):
        visited[node] += 1
        box_lo, box_hi = np.full(3, np.inf, np.float32), np.full(3, -np.inf, np.float32)
        children = 0
        for c in range(4):
            item = int(items[node, c])
            if lo[node, c, 0] >= 1e29:                      # an empty slot: its box is never entered
                assert item == 0 and (lo[node, c] == 1e30).all() and (hi[node, c] == 1e30).all()
                continue
            children += 1
            if item & LEAF:
                first, count = item & MASK, ((item >> 28) & 7) + 1
                reached[first:first + count] += 1
                s_lo, s_hi = prim_lo[first:first + count].min(0), prim_hi[first:first + count].max(0)
            else:
                s_lo, s_hi = subtree(item, prim_lo, prim_hi)
            pairs.append((lo[node, c], hi[node, c], s_lo, s_hi))
            box_lo, box_hi = np.minimum(box_lo, s_lo), np.maximum(box_hi, s_hi)
        assert 1 <= children <= 4
        return box_lo, box_hi

    return subtree, reached, visited, pairs


def check(w, lo, hi):
    subtree, reached, visited, pairs = walk(w)
    subtree(0, lo[w.order], hi[w.order])
    np.testing.assert_array_equal(reached, 1)      # every primitive in exactly one leaf
    np.testing.assert_array_equal(visited, 1)      # every node reachable, once
    for c_lo, c_hi, s_lo, s_hi in pairs:            # child boxes are exactly their subtree's bounds
        np.testing.assert_array_equal(c_lo, s_lo)
        np.testing.assert_array_equal(c_hi, s_hi)


@pytest.mark.parametrize("method", ["lbvh", "sah"])
def test_collapse_is_a_valid_bvh4(method):
    m = trimesh.creation.torus(1.0, 0.3, major_sections=32, minor_sections=16)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    b = build(lo, hi, method)
    w = bvh_wide.collapse(b)
    check(w, lo, hi)
    assert w.nodes.shape == (w.node_count, 28)
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


def test_refit_of_the_source_shows_in_the_nodes():
    m = trimesh.creation.icosphere(subdivisions=2)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    b = build(lo, hi, "sah")
    w = bvh_wide.collapse(b)
    moved = (m.vertices * [2.0, 0.5, 1.0])[m.faces].astype(np.float32)
    b.refit(*triangle_bounds(moved))
    check(w, *triangle_bounds(moved))


def test_relinked_offsets_nodes_and_maps_leaves():
    m = trimesh.creation.icosphere(subdivisions=2)
    lo, hi = triangle_bounds(m.triangles.astype(np.float32))
    w = bvh_wide.collapse(build(lo, hi, "sah"))
    items = w.nodes.view(np.uint32)[:, 24:]
    moved = w.relinked(lambda slot: slot + 1000, 7).view(np.uint32)
    np.testing.assert_array_equal(moved[:, :24], w.nodes.view(np.uint32)[:, :24])
    leaf, inner = (items & LEAF) != 0, ((items & LEAF) == 0) & (w.slots >= 0)
    np.testing.assert_array_equal(moved[:, 24:][leaf], items[leaf] + 1000)
    np.testing.assert_array_equal(moved[:, 24:][inner], items[inner] + 7)
    np.testing.assert_array_equal(moved[:, 24:][w.slots < 0], 0)
