"""Regenerate ``python/uasnav/mission/data/survey_models.json``: the built-in survey predictor
calibrated at each speed of :data:`uasnav.mission.planner.MODEL_SPEEDS` (deterministic)."""

from __future__ import annotations

import json

from uasnav.mission.planner import CALIBRATION_RUNS, MODEL_SPEEDS, MODELS_FILE, build_predictor


def main() -> None:
    models = {f"{v:g}": build_predictor(v).to_dict() for v in MODEL_SPEEDS}
    doc = {
        "what": "kinematic survey predictors with time bounds, one per speed (m/s)",
        "calibration_runs": CALIBRATION_RUNS,
        "models": models,
    }
    MODELS_FILE.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")
    print(f"wrote {MODELS_FILE}")


if __name__ == "__main__":
    main()
