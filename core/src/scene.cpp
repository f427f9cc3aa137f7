#include "drape/core/scene.h"

#include "drape/ccd/input_file.h"

#include "scene_node.h"

#include <algorithm>
#include <initializer_list>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

namespace drape {

namespace {

using scene_json::describe;
using scene_json::format_number;
using scene_json::json;
using scene_json::Node;
using scene_json::read_material;

// Bounds that keep counts in an int and a run finite.
constexpr int MAX_FRAME_STEPS = 100000;
constexpr int MAX_FRAMES = 10000000;
// No scene needs more; describing a value nested deeper could overflow the stack.
constexpr std::size_t MAX_JSON_DEPTH = 64;

Transform read_transform(const Node& n) {
  n.allow({"translate", "rotate", "scale"});
  Transform t;
  if (n.has("translate")) t.translate = n.at("translate").vec3_within(MAX_COORDINATE, "m");
  if (n.has("rotate")) {
    const Node r = n.at("rotate");
    if (!r.raw().is_array() || r.size() != 4) r.fail("expected [degrees, axis x, axis y, axis z]");
    t.rotate_degrees = r.at(std::size_t(0)).number();
    t.rotate_axis = Vec3(r.at(1).number(), r.at(2).number(), r.at(3).number());
    if (!(t.rotate_axis.norm() > 0)) r.fail("the rotation axis must not be zero");
    // A length beyond a double's range normalises to zero or NaN.
    if (!std::isfinite(t.rotate_axis.norm())) r.fail("expected a rotation axis of finite length, found " + describe(r.raw()));
  }
  if (n.has("scale")) t.scale = n.at("scale").number_in(MIN_SCALE, MAX_SCALE, "from 1e-6 to 1e6");
  return t;
}

Motion read_motion(const Node& n) {
  n.allow({"velocity", "angular_velocity", "center", "start", "end"});
  Motion m;
  if (n.has("velocity")) m.velocity = n.at("velocity").vec3_within(MAX_SPEED, "m/s");
  if (n.has("angular_velocity")) m.angular_velocity = n.at("angular_velocity").vec3_within(MAX_ANGULAR_SPEED, "rad/s");
  if (n.has("center")) m.center = n.at("center").vec3_within(MAX_COORDINATE, "m");
  if (n.has("start")) m.start = n.at("start").non_negative();
  if (n.has("end")) m.end = n.at("end").non_negative();
  if (!(m.end > m.start)) n.fail("'end' must be later than 'start'");
  return m;
}

Box read_box(const Node& n) {
  n.allow({"min", "max"});
  Box b{n.at("min").vec3_within(MAX_COORDINATE, "m"), n.at("max").vec3_within(MAX_COORDINATE, "m")};
  if (!(b.min.array() <= b.max.array()).all()) n.fail("expected min <= max in every coordinate");
  return b;
}

Ball read_ball(const Node& n) {  // a sphere obstacle's or a handle's {center, radius}
  n.allow({"center", "radius"});
  return {n.at("center").vec3_within(MAX_COORDINATE, "m"), n.at("radius").number_in(MIN_LENGTH, MAX_SIZE, "from 1e-6 to 1e4 (m)")};
}

// A render section (the scene's or a cloth's), kept as text: the renderer reads it.
std::string render_section(const Node& r) {
  if (!r.raw().is_object()) r.fail("expected an object");
  return r.raw().dump();
}

ClothSpec read_cloth(const Node& n) {
  n.allow({"mesh", "grid", "transform", "material", "velocity", "render"});
  ClothSpec c;
  if (n.has("grid") == n.has("mesh")) n.fail("expected exactly one of 'grid' (the built-in generator) or 'mesh' (a file)");
  if (n.has("grid")) {
    const Node g = n.at("grid");
    g.allow({"size", "resolution", "diagonals"});
    GridSpec spec;
    if (g.has("size")) {
      spec.size = g.at("size").vec2();
      if (!(spec.size.minCoeff() > 0) || !(spec.size.maxCoeff() <= MAX_SIZE))
        g.at("size").fail("expected two sizes > 0 and at most " + format_number(MAX_SIZE) + " m");
    }
    if (g.has("resolution")) {
      const Node r = g.at("resolution");
      if (!r.raw().is_array() || r.size() != 2) r.fail("expected [quads along x, quads along y]");
      spec.resolution = {r.at(std::size_t(0)).integer_in(1, 4096), r.at(1).integer_in(1, 4096)};
    }
    if (g.has("diagonals")) {
      const std::string d = g.at("diagonals").one_of({"alternate", "forward", "backward"});
      spec.diagonals = d == "forward" ? GridDiagonals::Forward : d == "backward" ? GridDiagonals::Backward : GridDiagonals::Alternate;
    }
    c.grid = spec;
  } else {
    c.mesh_file = n.at("mesh").file_path();
  }
  if (n.has("transform")) c.transform = read_transform(n.at("transform"));
  if (n.has("velocity")) c.velocity = n.at("velocity").vec3_within(MAX_SPEED, "m/s");
  if (n.has("render")) c.render_json = render_section(n.at("render"));
  if (n.has("material")) read_material(n.at("material"), c.grid.has_value(), c.material);
  return c;
}

HandleSpec read_handle(const Node& n, std::size_t cloth_count) {
  n.allow({"cloth", "nodes", "corners", "box", "ball", "motion"});
  HandleSpec h;
  if (n.has("cloth")) h.cloth = n.at("cloth").integer_in(0, int(cloth_count) - 1);
  if (n.has("nodes"))
    for (const Node& i : n.at("nodes").array(1)) h.nodes.push_back(i.integer_in(0, std::numeric_limits<int>::max()));
  if (n.has("corners"))
    for (const Node& c : n.at("corners").array(1))
      h.corners.push_back(c.one_of({"bottom-left", "bottom-right", "top-left", "top-right"}));
  if (n.has("box")) h.box = read_box(n.at("box"));
  if (n.has("ball")) h.ball = read_ball(n.at("ball"));
  if (h.nodes.empty() && h.corners.empty() && !h.box && !h.ball)
    n.fail("expected 'nodes', 'corners', 'box' or 'ball' to choose the pinned vertices");
  if (n.has("motion")) h.motion = read_motion(n.at("motion"));
  return h;
}

ObstacleSpec read_obstacle(const Node& n) {
  n.allow({"sphere", "plane", "mesh", "transform", "motion"});
  ObstacleSpec o;
  const int kinds = n.has("sphere") + n.has("plane") + n.has("mesh");
  if (kinds != 1) n.fail("expected exactly one of 'sphere', 'plane' or 'mesh'");
  if (n.has("sphere")) {
    const Ball ball = read_ball(n.at("sphere"));
    o.kind = ObstacleSpec::Kind::Sphere;
    o.center = ball.center, o.radius = ball.radius;
  } else if (n.has("plane")) {
    const Node p = n.at("plane");
    p.allow({"point", "normal"});
    o.kind = ObstacleSpec::Kind::Plane;
    if (p.has("point")) o.point = p.at("point").vec3_within(MAX_COORDINATE, "m");
    if (p.has("normal")) o.normal = p.at("normal").vec3();
    if (!(o.normal.norm() > 0)) p.at("normal").fail("the normal must not be zero");
    // A length beyond a double's range normalises to zero or NaN.
    if (!std::isfinite(o.normal.norm())) p.at("normal").fail("expected a normal of finite length, found " + describe(p.at("normal").raw()));
    o.normal.normalize();
  } else {
    o.kind = ObstacleSpec::Kind::Mesh;
    o.mesh_file = n.at("mesh").file_path();
  }
  if (n.has("transform")) {
    if (o.kind != ObstacleSpec::Kind::Mesh) n.at("transform").fail("only a mesh obstacle takes a transform");
    o.transform = read_transform(n.at("transform"));
  }
  if (n.has("motion")) o.motion = read_motion(n.at("motion"));
  return o;
}

// Line and column of a byte offset, for JSON syntax errors.
std::string line_and_column(const std::string& text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < std::min(byte, text.size()); ++i) {
    if (text[i] == '\n') ++line, column = 1;
    else ++column;
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column > 1 ? column - 1 : 1);
}

// Checks what nlohmann's parser lets through and the scene must not hold: nesting deeper
// than MAX_JSON_DEPTH (a value that deep would overflow the stack of every recursive reader
// after the parser) and a key given twice in one object (the parser keeps the last one
// silently). Runs before the parse, so on malformed text it may stop early or miss a key; the
// parse then reports the syntax error.
void check_structure(const std::string& text, const std::filesystem::path& file) {
  struct Level {
    bool object;
    std::set<std::string> keys;
  };
  std::vector<Level> levels;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '{' || c == '[') {
      if (levels.size() == MAX_JSON_DEPTH)
        throw SceneError(file.string() + ": " + line_and_column(text, i + 1) + ": expected at most " +
                         std::to_string(MAX_JSON_DEPTH) + " levels of nested arrays and objects");
      levels.push_back({c == '{', {}});
    } else if (c == '}' || c == ']') {
      if (!levels.empty()) levels.pop_back();
    } else if (c == '-' || std::isdigit(static_cast<unsigned char>(c))) {
      // A number beyond a double's range: the parser's message names no place.
      std::size_t end = i + 1;
      while (end < text.size() && (std::isdigit(static_cast<unsigned char>(text[end])) || text[end] == '.' ||
                                   text[end] == 'e' || text[end] == 'E' || text[end] == '+' || text[end] == '-'))
        ++end;
      const std::string number = text.substr(i, end - i);
      if (!std::isfinite(std::strtod(number.c_str(), nullptr)))
        throw SceneError(file.string() + ": " + line_and_column(text, i + 1) + ": the number " + number.substr(0, 40) +
                         " is beyond a double's range (about 1.8e308)");
      i = end - 1;
    } else if (c == '"') {
      const std::size_t start = i;
      for (++i; i < text.size() && text[i] != '"'; ++i)
        if (text[i] == '\\') ++i;
      std::size_t next = i + 1;
      while (next < text.size() && std::isspace(static_cast<unsigned char>(text[next]))) ++next;
      const bool is_key = !levels.empty() && levels.back().object && next < text.size() && text[next] == ':';
      if (!is_key) continue;
      // The key decoded, so that "a" and "\u0061" are the same key (as written if malformed).
      std::string key = text.substr(start, std::min(i + 1, text.size()) - start);
      try {
        key = json::parse(key).get<std::string>();
      } catch (const json::exception&) {
      }
      if (!levels.back().keys.insert(key).second)
        throw SceneError(file.string() + ": " + line_and_column(text, start + 1) + ": the key '" + key +
                         "' appears twice in the same object");
    }
  }
}

}  // namespace

Scene parse_scene(const std::string& text, const std::filesystem::path& file) {
  // Before the parse: a value nested deeper than the limit is refused before a tree of it is
  // built (16 MiB of '[' would allocate about a gigabyte).
  check_structure(text, file);
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    std::string reason = e.what();
    if (const auto p = reason.find("syntax error"); p != std::string::npos) reason = reason.substr(p);
    throw SceneError(file.string() + ": " + line_and_column(text, e.byte) + ": invalid JSON: " + reason);
  } catch (const json::exception& e) {  // e.g. a number too large for a double
    std::string reason = e.what();
    if (const auto p = reason.find("] "); p != std::string::npos) reason = reason.substr(p + 2);
    throw SceneError(file.string() + ": invalid JSON: " + reason);
  }
  const Node n(root, "", file);
  n.allow({"frame_time", "frame_steps", "timestep", "end_time", "frames", "gravity", "cloths", "handles",
           "obstacles", "wind", "friction", "solver", "collisions", "output", "bounds", "render", "limits"});
  Scene s;
  s.file = file;
  s.text = text;
  if (n.has("comment")) s.comment = n.at("comment").string();
  if (n.has("frame_time")) s.frame_time = n.at("frame_time").number_in(MIN_FRAME_TIME, MAX_FRAME_TIME, "from 1e-6 to 60 (s)");
  if (n.has("frame_steps") && n.has("timestep")) n.fail("give 'frame_steps' or 'timestep', not both");
  if (n.has("frame_steps")) s.frame_steps = n.at("frame_steps").integer_in(1, MAX_FRAME_STEPS);
  if (n.has("timestep")) {
    const Node t = n.at("timestep");
    const Scalar h = t.positive();
    const Scalar steps = s.frame_time / h;
    if (!(steps <= MAX_FRAME_STEPS))
      t.fail("expected at most " + std::to_string(MAX_FRAME_STEPS) + " steps per frame (frame_time / timestep)");
    if (std::abs(steps - std::round(steps)) > 1e-6 * steps || std::round(steps) < 1)
      t.fail("expected a timestep that divides frame_time (" + std::to_string(s.frame_time) + ") evenly");
    s.frame_steps = int(std::round(steps));
  }
  if (n.has("frames") && n.has("end_time")) n.fail("give 'frames' or 'end_time', not both");
  if (n.has("frames")) s.frames = n.at("frames").integer_in(1, MAX_FRAMES);
  if (n.has("end_time")) {
    const Scalar end = n.at("end_time").positive(), frames = std::round(end / s.frame_time);
    if (!(frames <= MAX_FRAMES)) n.at("end_time").fail("expected at most " + std::to_string(MAX_FRAMES) + " frames (end_time / frame_time)");
    // A whole number of frames (to a thousandth of one: a frame_time of 1/30 written with
    // seven digits gives 60.00006 frames in 2 s): a run ends on a frame, so another end would
    // be moved silently.
    if (!(frames >= 1 && std::abs(end / s.frame_time - frames) <= 1e-3)) {
      std::ostringstream what;
      what.precision(10);
      what << "expected a whole number of frames of " << s.frame_time << " s (frame_time); " << end << " s is "
           << end / s.frame_time << " frames: give 'frames', or an end_time such as " << std::max(Scalar(1), frames) * s.frame_time;
      n.at("end_time").fail(what.str());
    }
    s.frames = int(frames);
  }
  if (n.has("gravity")) s.gravity = n.at("gravity").vec3_within(MAX_ACCELERATION, "m/s^2");
  for (const Node& c : n.at("cloths").array(1)) s.cloths.push_back(read_cloth(c));
  if (n.has("handles"))
    for (const Node& h : n.at("handles").array()) s.handles.push_back(read_handle(h, s.cloths.size()));
  if (n.has("obstacles"))
    for (const Node& o : n.at("obstacles").array()) s.obstacles.push_back(read_obstacle(o));
  if (n.has("wind")) {
    const Node w = n.at("wind");
    w.allow({"velocity", "density", "drag"});
    WindSpec wind;
    if (w.has("velocity")) wind.velocity = w.at("velocity").vec3_within(MAX_SPEED, "m/s");
    if (w.has("density")) wind.density = w.at("density").up_to(MAX_FLUID_DENSITY, "kg/m^3", true);
    if (w.has("drag")) wind.drag = w.at("drag").up_to(MAX_COEFFICIENT, "", true);
    s.wind = wind;
  }
  if (n.has("friction")) s.friction = n.at("friction").up_to(MAX_COEFFICIENT, "", true);
  if (n.has("solver")) {
    const Node v = n.at("solver");
    v.allow({"type", "tolerance", "max_iterations", "max_halvings", "iterations", "chebyshev", "history", "factor_reuse", "release_solves"});
    if (v.has("type")) {
      const std::string type = v.at("type").one_of({"cholmod", "cg", "projective"});
      s.solver.kind = type == "cg" ? SolverKind::ConjugateGradient
                      : type == "projective" ? SolverKind::Projective : SolverKind::Cholmod;
    }
    s.solver.tolerance = default_tolerance(s.solver.kind);
    if (v.has("tolerance"))
      s.solver.tolerance = s.solver.kind == SolverKind::Projective ? v.at("tolerance").number_in(0, 1, "from 0 to 1")
                                                                   : v.at("tolerance").number_in(1e-16, 1, "from 1e-16 to 1");
    if (v.has("max_iterations")) s.solver.max_iterations = v.at("max_iterations").integer_in(1, 100000000);
    if (v.has("max_halvings")) s.solver.max_halvings = v.at("max_halvings").integer_in(0, 10);
    if (v.has("iterations")) s.solver.iterations = v.at("iterations").integer_in(1, MAX_PROJECTIVE_ITERATIONS);
    if (v.has("factor_reuse")) s.solver.factor_reuse = v.at("factor_reuse").integer_in(0, MAX_FACTOR_REUSE);
    if (v.has("release_solves")) s.solver.release_solves = v.at("release_solves").integer_in(0, MAX_RELEASE_SOLVES);
    if (v.has("history")) s.solver.history = v.at("history").integer_in(0, MAX_PROJECTIVE_HISTORY);
    if (v.has("chebyshev")) s.solver.chebyshev = v.at("chebyshev").number_in(0, MAX_CHEBYSHEV_RHO, "from 0 to 0.9999");
    // A key of another solver type is refused, not ignored: the user meant it to do something.
    const std::string type = v.has("type") ? v.at("type").string() : "cholmod";
    const auto only_for = [&](const char* key, std::initializer_list<SolverKind> kinds, const std::string& which) {
      if (v.has(key) && std::find(kinds.begin(), kinds.end(), s.solver.kind) == kinds.end())
        v.at(key).fail("applies to the " + which + " solver only, and this scene's 'type' is " + type);
    };
    only_for("tolerance", {SolverKind::ConjugateGradient, SolverKind::Projective}, "cg or projective");
    only_for("max_iterations", {SolverKind::ConjugateGradient}, "cg");
    only_for("factor_reuse", {SolverKind::Cholmod}, "cholmod");
    only_for("release_solves", {SolverKind::Cholmod}, "cholmod");
    for (const char* key : {"iterations", "history", "chebyshev"}) only_for(key, {SolverKind::Projective}, "projective");
    if (v.has("tolerance") && s.solver.kind == SolverKind::Projective && s.solver.history == 0)
      v.at("tolerance").fail("applies to L-BFGS (a 'history' above 0) only; local-global iterations ('history': 0) "
                             "run every one of their 'iterations'");
    if (v.has("chebyshev") && s.solver.history > 0)
      v.at("chebyshev").fail("applies to local-global iterations ('history': 0) only; L-BFGS (history " +
                             std::to_string(s.solver.history) + ") has no acceleration to set");
  }
  if (n.has("collisions")) {
    const Node c = n.at("collisions");
    c.allow({"self", "obstacles", "thickness", "method", "max_impulse_iterations", "max_zone_iterations", "feature_boxes",
             "self_culling", "self_in_solve"});
    if (c.has("self")) s.collisions.self = c.at("self").boolean();
    if (c.has("obstacles")) s.collisions.obstacles = c.at("obstacles").boolean();
    if (c.has("thickness")) s.collisions.thickness = c.at("thickness").number_in(0, MAX_THICKNESS, "from 0 to 1 (m)");
    if (c.has("method"))
      s.collisions.method = *ccd::parse_method(c.at("method").one_of({"cubic", "dnf", "vincent", "conservative"}));
    if (c.has("max_impulse_iterations")) s.collisions.max_impulse_iterations = c.at("max_impulse_iterations").integer_in(0, 1000);
    if (c.has("max_zone_iterations")) s.collisions.max_zone_iterations = c.at("max_zone_iterations").integer_in(0, 1000);
    if (c.has("feature_boxes")) s.collisions.feature_boxes = c.at("feature_boxes").boolean();
    if (c.has("self_culling")) s.collisions.self_culling = c.at("self_culling").boolean();
    if (c.has("self_in_solve")) s.collisions.self_in_solve = c.at("self_in_solve").boolean();
  }
  if (n.has("output")) {
    const Node o = n.at("output");
    o.allow({"folder", "mesh_format", "meshes"});
    if (o.has("folder")) s.output.folder = o.at("folder").string();
    if (o.has("folder") && s.output.folder.empty()) o.at("folder").fail("expected a folder's path, not an empty string");
    if (o.has("mesh_format")) s.output.mesh_format = o.at("mesh_format").one_of({"obj", "ply", "plyb", "stl", "stlb", "glb2", "collada"});
    if (o.has("meshes")) s.output.meshes = o.at("meshes").boolean();
  }
  if (s.output.folder.empty()) s.output.folder = std::filesystem::path("out") / file.stem();
  if (n.has("bounds")) s.bounds = read_box(n.at("bounds"));  // build_model checks it holds the cloths
  if (n.has("limits")) {
    const Node l = n.at("limits");
    l.allow({"energy_warn", "energy_stop", "stretch_warn", "stretch_stop"});
    RunLimits& limits = s.limits;
    if (l.has("energy_warn")) limits.energy_warn = l.at("energy_warn").number_in(0, 1e6, "from 0 to 1e6");
    if (l.has("energy_stop")) limits.energy_stop = l.at("energy_stop").number_in(0, 1e6, "from 0 to 1e6");
    if (l.has("stretch_warn")) limits.stretch_warn = l.at("stretch_warn").number_in(1, 1e6, "from 1 to 1e6");
    if (l.has("stretch_stop")) limits.stretch_stop = l.at("stretch_stop").number_in(1, 1e6, "from 1 to 1e6");
    if (!(limits.energy_stop >= limits.energy_warn)) l.fail("expected energy_stop >= energy_warn");
    if (!(limits.stretch_stop >= limits.stretch_warn)) l.fail("expected stretch_stop >= stretch_warn");
  }
  if (n.has("render")) s.render_json = render_section(n.at("render"));
  return s;
}

Scene load_scene(const std::filesystem::path& path) {
  std::string text;
  try {
    text = ccd::read_input_file(path, ccd::MAX_SCENE_BYTES, "scene file");
  } catch (const ccd::InputFileError& e) {
    throw SceneError(e.what());
  }
  return parse_scene(text, path);
}

}  // namespace drape
