// Load benchmark of `pectus serve` (issue 15): N clients on loopback, each on its own keep-alive
// connection, ask for a plan's score (POST /api/score, what the planner page asks after every move: both
// scenarios and the difference maps) or the whole plan (POST /api/plan) as fast as they are answered, for
// a given time, with random bars. Prints the latency percentiles, the requests answered per second and
// every error, as JSON.
//
//   pectus serve --patient-table CSV --model model.h5 --port 8765        (another terminal; wait for "ready")
//   serve_benchmark --url 'http://127.0.0.1:8765/?token=...' [--patient 57] [--clients 20] [--seconds 60]
//                   [--route score|plan] [--no-difference]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "shape/core/sample_statistics.h"

// clang-format off
// Last: <resolv.h>, which httplib.h includes, defines _res, a name Eigen's headers use.
#include <httplib.h>
// clang-format on

namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string line;
  std::getline(in, line);
  return line;
}

struct Flags {
  std::string url, patient = "57", route = "score";
  int clients = 20;
  double seconds = 60;
  bool difference = true;
};

Flags Parse(int argc, char** argv) {
  Flags f;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return argv[++i];
    };
    if (a == "--url")
      f.url = value();
    else if (a == "--patient")
      f.patient = value();
    else if (a == "--clients")
      f.clients = std::stoi(value());
    else if (a == "--seconds")
      f.seconds = std::stod(value());
    else if (a == "--route")
      f.route = value();
    else if (a == "--no-difference")
      f.difference = false;
    else
      throw std::runtime_error("unknown flag " + a);
  }
  if (f.url.empty()) throw std::runtime_error("--url is required (the URL `pectus serve` printed)");
  if (f.route != "score" && f.route != "plan") throw std::runtime_error("--route must be score or plan");
  if (f.clients < 1 || f.seconds <= 0) throw std::runtime_error("--clients and --seconds must be positive");
  return f;
}

// "http://127.0.0.1:8765/?token=abc" -> host, port, token.
void SplitUrl(const std::string& url, std::string* host, int* port, std::string* token) {
  const auto scheme = url.find("://");
  const auto start = scheme == std::string::npos ? 0 : scheme + 3;
  const auto colon = url.find(':', start), slash = url.find('/', start);
  *host = url.substr(start, colon - start);
  *port = std::stoi(url.substr(colon + 1, slash - colon - 1));
  const auto t = url.find("token=");
  if (t == std::string::npos) throw std::runtime_error("the URL has no token=");
  *token = url.substr(t + 6, url.find('&', t) - t - 6);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Flags flags = Parse(argc, argv);
    std::string host, token;
    int port = 0;
    SplitUrl(flags.url, &host, &port, &token);
    const httplib::Headers headers = {{"X-Pectus-Token", token}};
    // The patient made (or found made) before the clock starts.
    {
      httplib::Client client(host, port);
      client.set_read_timeout(300);
      const auto r = client.Get("/api/patients/" + flags.patient, headers);
      if (!r || r->status != 200) {
        std::cerr << "serve_benchmark: patient " << flags.patient << ": "
                  << (r ? std::to_string(r->status) + " " + r->body : "no answer") << "\n";
        return 1;
      }
    }
    std::mutex mutex;
    std::vector<double> latencies_ms;
    std::vector<std::string> errors;
    std::atomic<long> bytes{0};
    const auto start = Clock::now();
    const auto end = start + std::chrono::duration<double>(flags.seconds);
    std::vector<std::thread> clients;
    for (int c = 0; c < flags.clients; ++c) {
      clients.emplace_back([&, c] {
        httplib::Client client(host, port);
        client.set_keep_alive(true);
        client.set_tcp_nodelay(true);  // as browsers do
        client.set_read_timeout(60);
        std::mt19937 random(1000 + static_cast<unsigned>(c));
        std::uniform_real_distribution<double> position(0.6, 0.95), force(50, 600);
        std::vector<double> mine;
        std::vector<std::string> failed;
        long received = 0;
        while (Clock::now() < end) {
          json body = {{"patient", flags.patient},
                       {"bar", {{"position", position(random)}, {"force_n", force(random)}}}};
          if (flags.route == "score") body["difference"] = flags.difference;
          const auto t = Clock::now();
          const auto r = client.Post("/api/" + flags.route, headers, body.dump(), "application/json");
          const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
          if (!r) {
            failed.push_back("no answer: " + httplib::to_string(r.error()));
          } else if (r->status != 200) {
            failed.push_back(std::to_string(r->status) + " " + r->body.substr(0, 200));
          } else {
            mine.push_back(ms);
            received += static_cast<long>(r->body.size());
          }
        }
        bytes += received;
        std::lock_guard<std::mutex> lock(mutex);
        latencies_ms.insert(latencies_ms.end(), mine.begin(), mine.end());
        errors.insert(errors.end(), failed.begin(), failed.end());
      });
    }
    for (std::thread& t : clients) t.join();
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();
    json out = {
        {"route", "/api/" + flags.route},
        {"difference_maps", flags.route == "plan" || flags.difference},
        {"clients", flags.clients},
        {"seconds", wall},
        {"requests", latencies_ms.size()},
        {"requests_per_s", static_cast<double>(latencies_ms.size()) / wall},
        {"mean_answer_bytes", latencies_ms.empty() ? 0.0 : static_cast<double>(bytes) / latencies_ms.size()},
        {"errors", errors.size()},
        {"load_average_after", LoadAverage()}};
    if (!latencies_ms.empty()) {
      out["latency_ms"] = {{"p50", pectus::Quantile(latencies_ms, 0.50)},
                           {"p95", pectus::Quantile(latencies_ms, 0.95)},
                           {"p99", pectus::Quantile(latencies_ms, 0.99)},
                           {"max", pectus::Max(latencies_ms)}};
    }
    if (!errors.empty())
      out["first_errors"] =
          std::vector<std::string>(errors.begin(), errors.begin() + std::min<std::size_t>(5, errors.size()));
    std::cout << out.dump(1) << "\n";
    return errors.empty() ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "serve_benchmark: " << e.what() << "\n";
    return 2;
  }
}
