"""`python -m benchmarks samplers --quick`: one row per spp with both samplers' relMSE and FLIP
against the reference, and their ratio."""
import json

from benchmarks import harness


def test_samplers_quick_writes_a_row_per_spp_with_both_samplers(gpu, tmp_path):
    rc = harness.main(["samplers", "--quick", "--out", str(tmp_path), "--size", "8x8", "--spp", "1,16",
                       "--seeds", "2", "--reference-frames", "2", "--reference-spp", "16", "--max-bounces", "2"])
    assert rc == 0
    doc = json.loads((tmp_path / "samplers.json").read_text())
    assert doc["columns"][:8] == ["scene", "size", "bounces", "spp", "seeds", "relMSE sobol", "relMSE pcg", "pcg / sobol"]
    rows = [dict(zip(doc["columns"], r)) for r in doc["rows"]]
    assert [r["spp"] for r in rows] == [1, 16]
    for r in rows:
        assert r["scene"] == "cornell_box" and r["size"] == "8x8" and r["bounces"] == 2 and r["seeds"] == 2
        sobol, pcg = (float(r[k].split(" ± ")[0]) for k in ("relMSE sobol", "relMSE pcg"))
        assert sobol > 0 and pcg > 0 and abs(r["pcg / sobol"] - pcg / sobol) < 2e-3 * pcg / sobol + 1e-3
    # more paths, less error, whichever the sampler
    assert float(rows[1]["relMSE pcg"].split(" ± ")[0]) < float(rows[0]["relMSE pcg"].split(" ± ")[0])
    assert any("reference" in n for n in doc["notes"])
