// pectus serve: see planner_server.h. Routes, step by step: every request passes the Host and token checks
// (pre-routing), then one handler per route; a patient's planner, basis and binary arrays are made once
// on first use and kept (PatientCache); a plan is MakeNussPlan, as `pectus plan` makes it.
#include "apps/serve/planner_server.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "apps/serve/device_protocol.h"
#include "apps/serve/planner_page_files.h"
#include "apps/serve/trainer_sessions.h"
#include "planner_plugin/host/average_chest.h"
#include "planner_plugin/host/chest_registration.h"
#include "planner_plugin/host/nuss_plan.h"
#include "planner_plugin/host/plan_scoring.h"
#include "planner_plugin/host/planner_client.h"
#include "planner_plugin/host/planner_plugin_loader.h"
#include "shape/core/error.h"

// clang-format off
// Last: <resolv.h>, which httplib.h includes, defines _res, a name Eigen's headers use.
#include <httplib.h>
// clang-format on

namespace pectus::serve {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace pectus::planner;

// A request the client got wrong: answered with `status` and {"error": message}.
struct HttpError : std::runtime_error {
  HttpError(int status_code, const std::string& message) : std::runtime_error(message), status(status_code) {}
  int status;
};

void SendJson(httplib::Response& res, const json& body, int status = 200) {
  res.status = status;
  // With its parameter, cpp-httplib sends it as it is: it would compress plain application/json for a
  // browser with brotli at its slowest setting (tens of ms for a score's maps; nothing gained on the
  // loopback). apps/planner_page/embed.mjs does the same for the page's files.
  res.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace),
                  "application/json; charset=utf-8");
}

// A text body sent as it is. cpp-httplib compresses every text/* body for a browser that accepts brotli,
// at brotli's slowest setting: a trainer session's record of 28 000 ticks (2.5 MB) took 9 s in the Release
// build and 29 s under the sanitizers (2026-11-29). A body of known length from a content provider is
// never compressed.
void SendText(httplib::Response& res, std::string body, const char* content_type) {
  auto text = std::make_shared<const std::string>(std::move(body));
  res.set_content_provider(text->size(), content_type,
                           [text](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                             return sink.write(text->data() + offset, length);
                           });
}

void SendError(httplib::Response& res, int status, const std::string& message) {
  SendJson(res, {{"error", message}}, status);
}

// Little-endian float32 / uint32 arrays appended to a byte string.
void AppendFloats(std::string* out, const double* values, std::size_t count) {
  const std::size_t at = out->size();
  out->resize(at + 4 * count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto f = static_cast<float>(values[i]);
    std::memcpy(out->data() + at + 4 * i, &f, 4);
  }
}
void AppendUints(std::string* out, const std::int32_t* values, std::size_t count) {
  const std::size_t at = out->size();
  out->resize(at + 4 * count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto u = static_cast<std::uint32_t>(values[i]);
    std::memcpy(out->data() + at + 4 * i, &u, 4);
  }
}
void AppendPoints(std::string* out, const Points3& points) {
  // Points3 is #points by 3, row-major: x, y, z of each point in turn.
  AppendFloats(out, points.data(), static_cast<std::size_t>(points.size()));
}
void AppendFaces(std::string* out, const TriangleMesh& mesh) {
  AppendUints(out, mesh.faces.data(), static_cast<std::size_t>(mesh.faces.size()));  // row-major
}

json LandmarksJson(const LandmarkSet& set) {
  json out = json::array();
  for (const Landmark& l : set.items) {
    out.push_back({{"label", l.label}, {"position", {l.position.x(), l.position.y(), l.position.z()}}});
  }
  return out;
}

Points3 Positions(const LandmarkSet& set) {
  Points3 out(static_cast<Eigen::Index>(set.size()), 3);
  for (std::size_t i = 0; i < set.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = set.items[i].position;
  return out;
}

json TransformJson(const ChestRegistrationResult& r) {
  const Eigen::Matrix4d M = r.T_target_source.Matrix();
  json rows = json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({M(i, 0), M(i, 1), M(i, 2), M(i, 3)});
  return rows;
}

// A difference map (mm per average-chest vertex; NaN, written null, outside the region) to 0.1 µm: a
// third of the bytes of full doubles, and far finer than the 0.01 mm any figure is held to.
json DifferenceJson(const Eigen::VectorXd& d) {
  json out = json::array();
  for (Eigen::Index i = 0; i < d.size(); ++i)
    out.push_back(std::isfinite(d[i]) ? std::round(d[i] * 1e4) / 1e4 : d[i]);
  return out;
}

// ---- request validation -------------------------------------------------------------------------------

json ParseBody(const httplib::Request& req) {
  try {
    json body = json::parse(req.body);
    if (!body.is_object()) throw HttpError(400, "the request body must be a JSON object");
    return body;
  } catch (const json::parse_error& e) {
    throw HttpError(400, std::string("malformed JSON: ") + e.what());
  }
}

double Number(const json& object, const char* key, double lo, double hi, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) throw HttpError(400, where + "." + key + " is missing");
  if (!it->is_number()) throw HttpError(400, where + "." + key + " must be a number");
  const double value = it->get<double>();
  if (!std::isfinite(value) || value < lo || value > hi) {
    std::ostringstream text;
    text << where << "." << key << " = " << value << " is outside [" << lo << ", " << hi << "]";
    throw HttpError(400, text.str());
  }
  return value;
}

int Integer(const json& object, const char* key, int lo, int hi, int fallback, const std::string& where) {
  if (!object.contains(key)) return fallback;
  const json& v = object.at(key);
  if (!v.is_number_integer() || v.get<std::int64_t>() < lo || v.get<std::int64_t>() > hi) {
    throw HttpError(400, where + "." + key + " must be an integer in [" + std::to_string(lo) + ", " +
                             std::to_string(hi) + "]");
  }
  return v.get<int>();
}

// Longer than any sternum: bars in mm are checked against this before the patient's planner exists.
constexpr double kLongestSternumMm = 1000.0;

// {"position": 0.85, "position_in_mm": false, "force_n": 200}
BarPlacement ParseBar(const json& body, const char* key, double sternal_length_mm) {
  const auto it = body.find(key);
  if (it == body.end() || !it->is_object()) throw HttpError(400, std::string(key) + " must be an object");
  const json& bar = *it;
  bool in_mm = false;
  if (bar.contains("position_in_mm")) {
    if (!bar.at("position_in_mm").is_boolean())
      throw HttpError(400, std::string(key) + ".position_in_mm must be true or false");
    in_mm = bar.at("position_in_mm").get<bool>();
  }
  const double position = Number(bar, "position", 0.0, in_mm ? sternal_length_mm : 1.0, key);
  const double force = Number(bar, "force_n", 1e-3, 1e5, key);
  return {position, in_mm, force};
}

// ---- the patients ---------------------------------------------------------------------------------------

// The ids of a patient table: the first field of every row after the header.
std::vector<std::string> TableIds(const fs::path& table) {
  std::ifstream in(table);
  if (!in) ThrowBadInput(table.string(), "cannot open the patient table");
  std::vector<std::string> ids;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::string id = line.substr(0, line.find(','));
    id.erase(0, id.find_first_not_of(" \t\""));
    id.erase(id.find_last_not_of(" \t\"") + 1);
    if (!id.empty()) ids.push_back(id);
  }
  return ids;
}

// One patient's planner, its response basis and what the page downloads, made once.
struct PatientSession {
  std::mutex mutex;  // the planner is used by one request at a time
  std::unique_ptr<PlannerClient> planner;
  ChestRegistrationResult registration;  // T_average_patient, as MakeNussPlan registers
  std::unique_ptr<PlanScorer> scorer;    // the patient's chests against the average, in that frame
  PlanScore before;                      // the unoperated chest's score
  json info;
  std::string bone, skin, landmarks, basis;  // the binary arrays (docs/planner.md)
  std::string failure;                       // why it could not be made (then every request says so)
};

}  // namespace

bool ConstantTimeEquals(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(static_cast<unsigned char>(a[i]) ^ static_cast<unsigned char>(b[i]));
  return diff == 0;
}

bool PlannerServerOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (patient_table.empty()) return fail("--patient-table is required");
  if (model.empty()) return fail("--model (the average chest) is required");
  if (port < 0 || port > 65535) return fail("--port must be in [0, 65535]");
  if (device_port < -1 || device_port > 65535) return fail("--device-port must be in [0, 65535]");
  if (max_body_bytes < 1024) return fail("the request body limit must be at least 1024 bytes");
  if (threads < 1 || threads > 64) return fail("threads must be in [1, 64]");
  if (max_patients < 1) return fail("at least one patient must be kept in memory");
  if (!(table_step_mm >= 0.01 && table_step_mm <= 2.0)) return fail("the table step must be in [0.01, 2] mm");
  if (!token.empty() && token.size() < 16) return fail("a token must have at least 16 characters");
  return true;
}

struct PlannerServer::State {
  PlannerServerOptions options;
  std::unique_ptr<PlannerPlugin> plugin;
  PectusPlannerOptions planner_options{};
  AverageChest average;
  std::string average_mesh;  // binary
  json average_info, patients_json;
  std::map<std::string, PectusPlannerPatient> patients;
  std::mutex cache_mutex;
  std::list<std::pair<std::string, std::shared_ptr<PatientSession>>> cache;  // most recent first
  httplib::Server http;
  std::thread thread;
  std::vector<std::string> ids;                   // the table's, in its order
  std::thread prepare;                            // Prepare()'s
  std::string prepare_failure;                    // its reason if it could not (read after prepare is joined)
  std::unique_ptr<TrainerSessions> trainers;      // the trainer's sessions (issue 16)
  std::unique_ptr<DeviceProtocolServer> devices;  // their outside drivers (--device-port)
  int port = 0;
  std::mutex run_mutex;
  std::condition_variable stopped_cv;
  bool stopped = false;

  std::shared_ptr<PatientSession> Session(const std::string& id);
  void MakeSession(const std::string& id, PatientSession* s) const;
  bool Allowed(const httplib::Request& req, httplib::Response& res) const;
  void Routes();
  json Plan(const json& body);
  json Score(const json& body);
  void TrainerRoutes();
  json BarOutcome(const std::string& id, double level_z_mm);
};

// ---- a patient's session: planner, registration, basis and the page's coefficient table ----------------

void PlannerServer::State::MakeSession(const std::string& id, PatientSession* s) const {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  json timings;
  auto t = Clock::now();
  const PectusPlannerPatient& patient = patients.at(id);
  s->planner = std::make_unique<PlannerClient>(*plugin, patient, planner_options);
  PlannerClient& p = *s->planner;
  timings["planner"] = since(t);
  t = Clock::now();
  const PlanScoreOptions score;
  s->registration = RegisterChestByLandmarks(
      p.reference_landmarks(), AnteriorDirection(p.skin(), "patient skin"), average.landmarks,
      AnteriorDirection(average.mesh, "average chest"), score.registration);
  s->scorer = std::make_unique<PlanScorer>(p.skin(), p.reference_skin(), s->registration, average, score);
  s->before = s->scorer->Score(p.skin().vertices.positions);
  timings["scorer"] = since(t);
  t = Clock::now();
  const PectusPlannerBasisSummary summary =
      options.basis.empty() ? p.BuildBasis() : p.LoadBasis(options.basis);
  timings["basis"] = since(t);
  t = Clock::now();

  // The page's coefficient table (docs/planner.md, "Planner in the browser"): the plugin's own basis
  // (interface version 4), its modes U_r (3 #points: bone vertices, skin vertices, skin landmarks) and
  // its coefficients per newton c_k at bar levels every table_step_mm along the sternum; the page
  // interpolates c linearly between levels and multiplies by U_r, as the plugin's deform call does at
  // the level itself.
  const double length = p.measurements().sternal_length_mm;
  const Points3& bone0 = p.bone().vertices.positions;
  const Points3& skin0 = p.skin().vertices.positions;
  const Points3 landmarks0 = Positions(p.skin_landmarks());
  const double h = options.table_step_mm;
  std::vector<double> levels, lift, coefficients;
  Eigen::VectorXd c;
  for (int k = 0; k * h <= length + 1e-9; ++k) {
    double per_n = 0;
    if (!p.BasisCoefficients({k * h, true, 1.0}, &c, &per_n)) {
      if (!levels.empty()) break;  // past the sternum's end
      continue;                    // not yet on it
    }
    levels.push_back(k * h);
    lift.push_back(per_n);
    coefficients.insert(coefficients.end(), c.data(), c.data() + c.size());
  }
  if (levels.size() < 2)
    ThrowFailure("patient " + id + ": the bar reaches the sternum at fewer than 2 levels");
  const auto modes = p.BasisModes();
  const Eigen::Index rows = modes.rows(), rank = modes.cols();
  if (rows != 3 * (bone0.rows() + skin0.rows() + landmarks0.rows()))
    ThrowFailure("patient " + id + ": the basis has " + std::to_string(rows) +
                 " rows, not 3 per output point");
  timings["table"] = since(t);
  s->basis.clear();
  AppendFloats(&s->basis, lift.data(), lift.size());
  AppendFloats(&s->basis, coefficients.data(), coefficients.size());  // level after level
  s->basis.append(reinterpret_cast<const char*>(modes.data()),
                  sizeof(float) * static_cast<std::size_t>(modes.size()));
  const auto K = static_cast<Eigen::Index>(levels.size());

  s->bone.clear();
  AppendPoints(&s->bone, bone0);
  AppendFaces(&s->bone, p.bone());
  const Eigen::Matrix<std::int32_t, Eigen::Dynamic, 1> regions = p.bone_regions().cast<std::int32_t>();
  AppendUints(&s->bone, regions.data(), static_cast<std::size_t>(regions.size()));
  s->skin.clear();
  AppendPoints(&s->skin, skin0);
  AppendPoints(&s->skin, p.reference_skin());
  AppendFaces(&s->skin, p.skin());
  s->landmarks.clear();
  AppendPoints(&s->landmarks, landmarks0);
  AppendPoints(&s->landmarks, Positions(p.bone_landmarks()));

  const PectusPlannerMeasurements& m = p.measurements();
  json labels = json::array(), bone_labels = json::array();
  for (const Landmark& l : p.skin_landmarks().items) labels.push_back(l.label);
  for (const Landmark& l : p.bone_landmarks().items) bone_labels.push_back(l.label);
  s->info = {{"id", id},
             {"sternal_length_mm", length},
             {"depression_mm", m.depression_mm},
             {"linear_range_lift_mm", LinearRangeLiftMm(m.depression_mm)},
             {"haller_index", m.haller_index},
             {"bone",
              {{"vertices", bone0.rows()},
               {"faces", p.bone().faces.rows()},
               {"regions", {"sternum", "rib", "costal_cartilage"}}}},
             {"skin", {{"vertices", skin0.rows()}, {"faces", p.skin().faces.rows()}}},
             {"landmarks", {{"skin", labels}, {"bone", bone_labels}}},
             {"T_average_patient", TransformJson(s->registration)},
             {"basis",
              {{"levels", K},
               {"rank", rank},
               {"first_mm", levels.front()},
               {"step_mm", h},
               {"rows", rows},
               {"plugin_rank", summary.rank},
               {"from", options.basis.empty() ? "built" : options.basis.string()},
               {"seconds", summary.seconds}}},
             {"timings_s", timings}};
}

std::shared_ptr<PatientSession> PlannerServer::State::Session(const std::string& id) {
  if (!patients.count(id))
    throw HttpError(404, "no patient '" + id + "' in " + options.patient_table.string());
  std::shared_ptr<PatientSession> s;
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    for (auto it = cache.begin(); it != cache.end(); ++it) {
      if (it->first == id) {
        s = it->second;
        cache.splice(cache.begin(), cache, it);
        break;
      }
    }
    if (!s) {
      s = std::make_shared<PatientSession>();
      cache.emplace_front(id, s);
      while (static_cast<int>(cache.size()) > options.max_patients)
        cache.pop_back();  // in-flight users keep theirs
    }
  }
  std::unique_lock<std::mutex> lock(s->mutex);
  if (!s->planner && s->failure.empty()) {
    try {
      MakeSession(id, s.get());
    } catch (const std::exception& e) {
      s->planner.reset();
      s->failure = e.what();
    }
  }
  if (!s->failure.empty()) throw HttpError(500, "patient " + id + ": " + s->failure);
  return s;
}

// ---- a plan, as `pectus plan` makes it
// ---------------------------------------------------------------------

json PlannerServer::State::Plan(const json& body) {
  // Step 1: the request checked in full before any work (a bar in mm against the sternum's length below).
  const auto it = body.find("patient");
  if (it == body.end() || !it->is_string())
    throw HttpError(400, "patient must be a string (an id of the table)");
  NussPlanOptions options;
  options.scenario_a = ParseBar(body, "bar", kLongestSternumMm);
  if (body.contains("compare")) options.scenario_b = ParseBar(body, "compare", kLongestSternumMm);
  options.search = false;
  if (body.contains("search")) {
    const json& search = body.at("search");
    if (!search.is_object()) throw HttpError(400, "search must be an object ({} for the defaults)");
    options.search = true;
    PlacementSearchOptions& o = options.search_options;
    o.positions = Integer(search, "positions", 2, 40, 10, "search");
    o.forces = Integer(search, "forces", 2, 61, 31, "search");
    o.golden_iterations = Integer(search, "refinements", 0, 30, 16, "search");
    if (search.contains("from")) o.position_from = Number(search, "from", 0.0, 1.0, "search");
    if (search.contains("to")) o.position_to = Number(search, "to", 0.0, 1.0, "search");
    if (search.contains("max_force_n")) o.force_max_n = Number(search, "max_force_n", 1.0, 1e5, "search");
    std::string why;
    if (!o.IsValid(&why)) throw HttpError(400, "search: " + why);
  }
  // Step 2: the patient's planner (made on first use), then the bars against its sternum.
  const std::shared_ptr<PatientSession> s = Session(it->get<std::string>());
  std::lock_guard<std::mutex> lock(s->mutex);
  const PlannerClient& p = *s->planner;
  const double length = p.measurements().sternal_length_mm;
  options.scenario_a = ParseBar(body, "bar", length);
  if (body.contains("compare")) options.scenario_b = ParseBar(body, "compare", length);
  // Step 3: the plan, as `pectus plan` makes it.
  NussPlan plan;
  try {
    plan = MakeNussPlan(p, average, options);
  } catch (const Error& e) {
    throw HttpError(e.kind() == ErrorKind::kFailure ? 500 : 400, e.what());
  }
  json out = plan.ToJson();
  out["patient"] = it->get<std::string>();
  // The difference to the average chest per average-chest vertex (mm; null outside the region), for the
  // page's colour map, and the average chest's anterior direction it is measured along.
  for (std::size_t i = 0; i < plan.scenarios.size(); ++i)
    out["scenarios"][i]["difference_mm"] = DifferenceJson(plan.scenarios[i].score.difference_mm);
  out["before"]["difference_mm"] = DifferenceJson(plan.before.difference_mm);
  return out;
}

// ---- a live score: the scenarios from the exact basis --------------------------------------------------

json PlannerServer::State::Score(const json& body) {
  // Step 1: the request checked in full before any work.
  const auto it = body.find("patient");
  if (it == body.end() || !it->is_string())
    throw HttpError(400, "patient must be a string (an id of the table)");
  ParseBar(body, "bar", kLongestSternumMm);
  if (body.contains("compare")) ParseBar(body, "compare", kLongestSternumMm);
  bool difference = true;
  if (body.contains("difference")) {
    if (!body.at("difference").is_boolean()) throw HttpError(400, "difference must be true or false");
    difference = body.at("difference").get<bool>();
  }
  // Step 2: the chests of scenarios A and B from the patient's basis (the deformer is the session's: one
  // request at a time, a fraction of a millisecond), then scored without the lock.
  const std::shared_ptr<PatientSession> s = Session(it->get<std::string>());
  std::vector<PlannedCase> cases;
  double depression = 0;
  {
    std::lock_guard<std::mutex> lock(s->mutex);
    const PlannerClient& p = *s->planner;
    const double length = p.measurements().sternal_length_mm;
    depression = p.measurements().depression_mm;
    const BarPlacement a = ParseBar(body, "bar", length);
    const double a_mm = a.position_in_mm ? a.position : a.position * length;
    const BarPlacement b = body.contains("compare")
                               ? ParseBar(body, "compare", length)
                               : BarPlacement{std::max(0.0, a_mm - 20.0), true, a.force_n};
    try {
      cases = p.Deform({a, b}, false);
    } catch (const Error& e) {
      throw HttpError(400, e.what());
    }
  }
  json out = {{"patient", it->get<std::string>()}, {"from_basis", true}, {"before", s->before.ToJson()}};
  out["scenarios"] = json::array();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const PlanScenario scenario{i == 0 ? "A" : "B", cases[i], s->scorer->Score(cases[i].skin)};
    json j = ScenarioJson(scenario, depression, false);
    if (difference) j["difference_mm"] = DifferenceJson(scenario.score.difference_mm);
    out["scenarios"].push_back(std::move(j));
  }
  return out;
}

// ---- checks every request passes --------------------------------------------------------------------------

bool PlannerServer::State::Allowed(const httplib::Request& req, httplib::Response& res) const {
  const std::string host = req.get_header_value("Host");
  const std::string p = std::to_string(port);
  if (host != "127.0.0.1:" + p && host != "localhost:" + p) {
    SendError(res, 403, "the Host header must be 127.0.0.1:" + p + " or localhost:" + p);
    return false;
  }
  std::string given = req.get_param_value("token");
  if (given.empty()) given = req.get_header_value("X-Pectus-Token");
  if (given.empty()) {
    const std::string cookie = req.get_header_value("Cookie");
    const auto at = cookie.find("pectus_token=");
    if (at != std::string::npos) given = cookie.substr(at + 13, cookie.find(';', at) - at - 13);
  }
  if (!ConstantTimeEquals(given, options.token)) {
    SendError(res, 403, given.empty() ? "no token: open the URL `pectus serve` printed" : "wrong token");
    return false;
  }
  return true;
}

void PlannerServer::State::Routes() {
  http.set_payload_max_length(options.max_body_bytes);
  http.set_read_timeout(5, 0);
  http.set_write_timeout(10, 0);
  http.set_keep_alive_timeout(5);
  // Answers go out at once: without it, Nagle's algorithm holds a body back until the client acknowledges
  // the headers, which it delays by 40 ms.
  http.set_tcp_nodelay(true);
  const int threads = options.threads;
  http.new_task_queue = [threads] { return new httplib::ThreadPool(static_cast<std::size_t>(threads)); };
  http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    return Allowed(req, res) ? httplib::Server::HandlerResponse::Unhandled
                             : httplib::Server::HandlerResponse::Handled;
  });
  http.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
    try {
      std::rethrow_exception(ep);
    } catch (const HttpError& e) {
      SendError(res, e.status, e.what());
    } catch (const std::exception& e) {
      SendError(res, 500, e.what());
    } catch (...) {
      SendError(res, 500, "unknown failure");
    }
  });
  http.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    const std::string message = res.status == 413   ? "request body too large"
                                : res.status == 404 ? "no such path: " + req.path
                                : res.status == 400 ? "malformed request"
                                                    : "error " + std::to_string(res.status);
    SendError(res, res.status, message);
  });

  http.Get("/api/patients",
           [this](const httplib::Request&, httplib::Response& res) { SendJson(res, patients_json); });
  http.Get(R"(/api/patients/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
    SendJson(res, Session(req.matches[1])->info);
  });
  http.Get(R"(/api/patients/([^/]+)/(bone|skin|landmarks|basis))",
           [this](const httplib::Request& req, httplib::Response& res) {
             const auto s = Session(req.matches[1]);
             const std::string what = req.matches[2];
             const std::string& bytes = what == "bone"        ? s->bone
                                        : what == "skin"      ? s->skin
                                        : what == "landmarks" ? s->landmarks
                                                              : s->basis;
             res.set_content(bytes, "application/octet-stream");
           });
  // The C++ deform call itself, for checking the page's deformation from the coefficient table.
  http.Post("/api/deform", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = ParseBody(req);
    const auto id = body.find("patient");
    if (id == body.end() || !id->is_string())
      throw HttpError(400, "patient must be a string (an id of the table)");
    ParseBar(body, "bar", kLongestSternumMm);  // checked before any work
    const auto s = Session(id->get<std::string>());
    std::lock_guard<std::mutex> lock(s->mutex);
    const BarPlacement bar = ParseBar(body, "bar", s->planner->measurements().sternal_length_mm);
    std::vector<PlannedCase> c;
    try {
      c = s->planner->Deform({bar}, false);
    } catch (const Error& e) {
      throw HttpError(400, e.what());
    }
    const Points3& skin = c[0].skin;
    SendJson(res, {{"sternum_lift_mm", c[0].figures.sternum_lift_mm},
                   {"skin", std::vector<double>(skin.data(), skin.data() + skin.size())}});
  });
  http.Get("/api/average",
           [this](const httplib::Request&, httplib::Response& res) { SendJson(res, average_info); });
  http.Get("/api/average/mesh", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(average_mesh, "application/octet-stream");
  });
  http.Post("/api/plan", [this](const httplib::Request& req, httplib::Response& res) {
    SendJson(res, Plan(ParseBody(req)));
  });
  http.Post("/api/score", [this](const httplib::Request& req, httplib::Response& res) {
    SendJson(res, Score(ParseBody(req)));
  });
  TrainerRoutes();
  // The page: only the embedded files, by exact path.
  http.Get(R"(/[A-Za-z0-9_./-]*)", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string path = req.path == "/" ? "/index.html" : req.path;
    for (std::size_t i = 0; i < kPlannerPageFileCount; ++i) {
      const EmbeddedFile& f = kPlannerPageFiles[i];
      if (path == f.path) {
        res.set_content(reinterpret_cast<const char*>(f.data), f.size, f.mime);
        res.set_header("Cache-Control", "no-store");
        res.set_header("X-Content-Type-Options", "nosniff");
        if (path == "/index.html" && req.has_param("token")) {
          res.set_header("Set-Cookie",
                         "pectus_token=" + options.token + "; Path=/; HttpOnly; SameSite=Strict");
        }
        return;
      }
    }
    if (req.path.rfind("/api/", 0) == 0) throw HttpError(404, "no such API path: " + req.path);
    throw HttpError(404, "no such file: " + req.path);
  });
  // Any other method or path: JSON 404 (through the error handler). The page's route comes last: the first
  // pattern that matches answers.
}

// ---- the trainer (issue 16; docs/trainer.md, "The trainer in the planner page") ---------------------------

namespace {

std::string SessionId(const json& body) {
  const auto it = body.find("session");
  if (it == body.end() || !it->is_string() || it->get<std::string>().empty() ||
      it->get<std::string>().size() > 20)
    throw HttpError(400, "session must be a string (the id /api/trainer/start answered)");
  return it->get<std::string>();
}

// Runs a call of the trainer's sessions: an unknown session is 404, a finished one or a bad request 400,
// anything else 500.
template <typename Call>
auto Trainer(Call&& call) {
  try {
    return call();
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind("no trainer session", 0) == 0) throw HttpError(404, what);
    throw HttpError(e.kind() == ErrorKind::kFailure ? 500 : 400, what);
  }
}

}  // namespace

// The bar the session's tunnel is made for, and its outcome against the average chest, as the planner scores
// it: at the tunnel's level (its height below the notch, taken along the sternum), with the force that lifts
// the sternum by the depression, from the patient's exact basis.
json PlannerServer::State::BarOutcome(const std::string& id, double level_z_mm) {
  const std::shared_ptr<PatientSession> s = Session(id);
  std::lock_guard<std::mutex> lock(s->mutex);
  const PlannerClient& p = *s->planner;
  const double length = p.measurements().sternal_length_mm;
  const double mm = std::clamp(-level_z_mm, 0.0, length);
  Eigen::VectorXd c;
  double per_n = 0;
  if (!p.BasisCoefficients({mm, true, 1.0}, &c, &per_n) || !(per_n > 0))
    return {{"error", "the bar at the tunnel's level is off the sternum"}};
  const double force = p.measurements().depression_mm / per_n;
  const std::vector<PlannedCase> cases = p.Deform({{mm, true, force}}, false);
  const PlanScore score = s->scorer->Score(cases[0].skin);
  return {{"position_mm", mm},       {"position", mm / length},
          {"force_n", force},        {"sternum_lift_mm", cases[0].figures.sternum_lift_mm},
          {"score", score.ToJson()}, {"before", s->before.ToJson()}};
}

void PlannerServer::State::TrainerRoutes() {
  http.Post("/api/trainer/start", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = ParseBody(req);
    const auto id = body.find("patient");
    if (id == body.end() || !id->is_string())
      throw HttpError(400, "patient must be a string (an id of the table)");
    std::string introducer = "medium";
    if (body.contains("introducer")) {
      const json& i = body.at("introducer");
      if (!i.is_string() || (i != "small" && i != "medium" && i != "large"))
        throw HttpError(400, "introducer must be \"small\", \"medium\" or \"large\"");
      introducer = i.get<std::string>();
    }
    const auto s = Session(id->get<std::string>());
    std::lock_guard<std::mutex> lock(s->mutex);  // the trainer is made from the planner's ribcage
    SendJson(res, Trainer([&] { return trainers->Start(*s->planner, id->get<std::string>(), introducer); }));
  });
  http.Get(R"(/api/trainer/([0-9]+)/meshes)", [this](const httplib::Request& req, httplib::Response& res) {
    res.set_content(Trainer([&] { return trainers->Meshes(req.matches[1]); }), "application/octet-stream");
  });
  http.Post("/api/trainer/device", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = ParseBody(req);
    const std::string session = SessionId(body);
    const auto it = body.find("position");
    if (it == body.end() || !it->is_array() || it->size() != 3)
      throw HttpError(400, "position must be [x, y, z] in mm (the patient's frame)");
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) {
      const json& v = it->at(k);
      if (!v.is_number() || !std::isfinite(v.get<double>()) || std::abs(v.get<double>()) > 2000)
        throw HttpError(400, "position must hold three numbers within 2000 mm of the notch");
      p[k] = v.get<double>();
    }
    const auto buttons = static_cast<std::uint32_t>(Integer(body, "buttons", 0, 255, 0, "device"));
    SendJson(res, Trainer([&] { return trainers->Device(session, p, buttons); }));
  });
  http.Post("/api/trainer/finish", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string session = SessionId(ParseBody(req));
    json report = Trainer([&] { return trainers->Finish(session); });
    if (report.contains("score") && !report.contains("bar"))
      report["bar"] = BarOutcome(report["patient"].get<std::string>(), report["level_z_mm"].get<double>());
    SendJson(res, report);
  });
  http.Get(R"(/api/trainer/([0-9]+)/record)", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string id = req.matches[1];
    SendText(res, Trainer([&] { return trainers->Record(id); }), "text/plain; charset=utf-8");
    res.set_header("Content-Disposition", "attachment; filename=\"trainer_session_" + id + ".txt\"");
  });
}

// ---- the server
// ----------------------------------------------------------------------------------------------

PlannerServer::PlannerServer(PlannerServerOptions options) : state_(std::make_unique<State>()) {
  State& s = *state_;
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  if (options.token.empty()) {
    std::random_device random;
    static const char kHex[] = "0123456789abcdef";
    for (int i = 0; i < 32; ++i) options.token += kHex[random() % 16];
  }
  s.options = std::move(options);
  s.plugin = std::make_unique<PlannerPlugin>(PlannerPlugin::Find(s.options.plugin.string()));
  s.planner_options = PluginDefaultOptions(*s.plugin);
  if (s.options.cartilage_mpa > 0) s.planner_options.cartilage_youngs_modulus_mpa = s.options.cartilage_mpa;
  if (s.options.cell_mm > 0) s.planner_options.rib_cell_length_mm = s.options.cell_mm;
  if (s.options.soft_tissue_mm >= 0) s.planner_options.soft_tissue_mm = s.options.soft_tissue_mm;
  // Step 1: the average chest (a bad model fails before the server starts).
  s.average = LoadAverageChest(s.options.model, s.options.model_landmarks);
  AppendPoints(&s.average_mesh, s.average.mesh.vertices.positions);
  AppendFaces(&s.average_mesh, s.average.mesh);
  const Eigen::Vector3d anterior = AnteriorDirection(s.average.mesh, "average chest");
  s.average_info = {{"model", s.options.model.string()},
                    {"vertices", s.average.mesh.num_vertices()},
                    {"faces", s.average.mesh.faces.rows()},
                    {"landmarks", LandmarksJson(s.average.landmarks)},
                    {"anterior", {anterior.x(), anterior.y(), anterior.z()}},
                    {"grid", {{"columns", s.average.grid_columns}, {"rows", s.average.grid_rows}}}};
  // Step 2: the patients of the table, read through the plugin as `pectus plan` reads one.
  s.patients_json = json::array();
  for (const std::string& id : TableIds(s.options.patient_table)) {
    const PectusPlannerPatient p = ReadPlannerPatient(*s.plugin, s.options.patient_table, id);
    s.patients.emplace(id, p);
    s.ids.push_back(id);
    s.patients_json.push_back({{"id", id},
                               {"width_mm", p.width_mm / p.magnification},
                               {"depth_mm", p.depth_mm / p.magnification},
                               {"sternal_length_mm", p.sternal_length_mm},
                               {"depression_mm", p.depression_mm / p.magnification},
                               {"haller_index", p.ct_haller_index}});
  }
  if (s.patients.empty()) ThrowBadInput(s.options.patient_table.string(), "the table has no patient");
  // Step 3: the trainer's sessions; their records pass through a folder of this server's own.
  s.trainers = std::make_unique<TrainerSessions>(
      *s.plugin, fs::temp_directory_path() / ("pectus-serve-" + s.options.token.substr(0, 12)));

  s.Routes();
}

PlannerServer::~PlannerServer() { Stop(); }

void PlannerServer::Start() {
  State& s = *state_;
  if (s.options.port == 0) {
    s.port = s.http.bind_to_any_port(s.options.host);
  } else {
    s.port = s.http.bind_to_port(s.options.host, s.options.port) ? s.options.port : -1;
  }
  if (s.port <= 0) {
    ThrowFailure("cannot listen on " + s.options.host + ":" + std::to_string(s.options.port) +
                 " (in use? --port 0 picks a free one)");
  }
  if (s.options.device_port >= 0)
    s.devices = std::make_unique<DeviceProtocolServer>(s.trainers.get(), s.options.token, s.options.host,
                                                       s.options.device_port);
  s.thread = std::thread([&s] {
    s.http.listen_after_bind();
    std::lock_guard<std::mutex> lock(s.run_mutex);
    s.stopped = true;
    s.stopped_cv.notify_all();
  });
  // Answering before Start() returns: a Stop() before the thread listens would not stop it.
  std::unique_lock<std::mutex> lock(s.run_mutex);
  while (!s.http.is_running() && !s.stopped) {
    lock.unlock();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    lock.lock();
  }
}

void PlannerServer::Wait() {
  std::unique_lock<std::mutex> lock(state_->run_mutex);
  state_->stopped_cv.wait(lock, [this] { return state_->stopped; });
}

const std::vector<std::string>& PlannerServer::patient_ids() const { return state_->ids; }

void PlannerServer::Prepare(const std::string& id) {
  State& s = *state_;
  if (!s.patients.count(id)) ThrowUsage("no patient '" + id + "' in " + s.options.patient_table.string());
  WaitUntilPrepared();
  s.prepare_failure.clear();
  s.prepare = std::thread([&s, id] {
    try {
      s.Session(id);
    } catch (const std::exception& e) {
      s.prepare_failure = e.what();
    }
  });
}

bool PlannerServer::WaitUntilPrepared(std::string* why) {
  if (state_->prepare.joinable()) state_->prepare.join();
  if (why != nullptr) *why = state_->prepare_failure;
  return state_->prepare_failure.empty();
}

void PlannerServer::Stop() {
  if (!state_) return;
  state_->http.stop();
  if (state_->thread.joinable()) state_->thread.join();
  if (state_->prepare.joinable()) state_->prepare.join();
  state_->devices.reset();   // no driver's datagram after this
  state_->trainers.reset();  // every servo thread stopped
}

int PlannerServer::port() const { return state_->port; }
int PlannerServer::device_port() const { return state_->devices ? state_->devices->port() : -1; }
const std::string& PlannerServer::token() const { return state_->options.token; }
std::string PlannerServer::url() const {
  return "http://127.0.0.1:" + std::to_string(state_->port) + "/?token=" + state_->options.token;
}

}  // namespace pectus::serve
