"""demseis bench seismic prints one JSON line."""

import json

from demseis.generator.cli import main


def test_bench_seismic_prints_one_json_line(capsys):
    assert main(["bench", "seismic", "--nx", "64", "--nz", "36", "--repeats", "1"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1
    rec = json.loads(lines[0])
    assert rec["nx"] == 64 and rec["nz"] == 36
    assert rec["ms_snapshot_1f"] > 0 and rec["ms_snapshot_3f"] > 0
    assert set(rec["components_ms"]) >= {"rasterise", "background", "smooth_vp_rho",
                                         "convolution_1f", "convolution_3f"}
    assert main(["bench", "seismic", "--repeats", "0"]) == 2
