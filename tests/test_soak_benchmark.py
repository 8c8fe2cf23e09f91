"""The soak benchmark (benchmarks/soak.py, issue 57 item 3) in its quick form: both models
run a fraction of a second simulated, and the report holds sane samples and finite slopes.
Not a timing test."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pytest

from benchmarks import soak


def test_quick_soak_reports_samples_slopes_and_folder(tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    report_file, samples_file = tmp_path / "soak.json", tmp_path / "soak.csv"
    assert soak.main(["--quick", "--dir", str(tmp_path), "--json", str(report_file),
                      "--csv", str(samples_file)]) == 0
    printed = capsys.readouterr().out
    reports = json.loads(report_file.read_text(encoding="utf-8"))
    assert [r["model"] for r in reports] == ["example2", "guide_wire"]
    for r in reports:
        assert r["status"] == "completed"
        assert r["t_end"] == soak.QUICK[r["model"]]
        samples = r["samples"]
        assert len(samples) >= 5            # the first report and the windows' ends
        assert samples[-1]["t"] == pytest.approx(r["t_end"])
        assert all(b["t"] > a["t"] and b["steps"] > a["steps"]
                   for a, b in zip(samples, samples[1:], strict=False))
        for s in samples:
            assert s["rss_mb"] > 0 and s["open_files"] > 0 and s["threads"] >= 1
        for s in samples[1:]:
            assert 0 < s["step_us"] < 1e6 and s["cpu_us"] >= 0 and s["newton_per_step"] > 0
        assert set(r["slopes"]) == {"rss_mb_per_1000_steps", "rss_mb_per_simulated_s",
                                    "open_files_per_1000_steps",
                                    "step_time_percent_per_1000_steps",
                                    "cpu_per_step_percent_per_1000_steps",
                                    "newton_per_step_percent_per_1000_steps"}
        assert all(math.isfinite(s["value"]) for s in r["slopes"].values())
        assert r["output_files"] > len(samples) and r["output_mb"] > 0
        assert f"{r['model']}: {r['scenario']}" in printed
    assert printed.count("slopes over the") == 2
    assert not list(tmp_path.glob("flexmbs_soak_*"))        # the output folders are removed
    with samples_file.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == sum(len(r["samples"]) for r in reports)
    assert all(float(row["rss_mb"]) > 0 for row in rows)
