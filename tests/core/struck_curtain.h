#pragma once
// The struck curtain of issues 19 and 20 (test_energy.cpp, test_integrator.cpp): a 1 m cloth of
// 6 cm cells pinned along its top, struck at mid-height by a 10 cm ball moving at `speed` m/s
// (for 2.4 m), 25 frames of 10 steps, self-collision, the cloth's `material` (a JSON object).
#include <string>

inline std::string struck_curtain_json(const std::string& material, double speed, double friction) {
  return R"({"frame_time": 0.033333333333333333, "frame_steps": 10, "frames": 25,
    "cloths": [{"grid": {"size": [1.0, 1.0], "resolution": [16, 16]},
                "transform": {"translate": [0, 0, 1.5], "rotate": [90, 1, 0, 0]}, "material": )" +
         material + R"(}],
    "handles": [{"cloth": 0, "box": {"min": [-1, -1, 1.99], "max": [1, 1, 2.01]}}],
    "obstacles": [{"sphere": {"center": [0.05, -0.6, 1.45], "radius": 0.1},
                   "motion": {"velocity": [0, )" +
         std::to_string(speed) + R"(, 0], "end": )" + std::to_string(2.4 / speed) + R"(}}],
    "friction": )" + std::to_string(friction) + R"(, "collisions": {"self": true, "thickness": 0.005}})";
}
