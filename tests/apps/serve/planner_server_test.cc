// `pectus serve`'s server (apps/serve/planner_server.h) through HTTP, as a browser or an attacker would
// call it (httplib's client and raw sockets): every line of the issue's safety list, each with its
// status and a JSON message; 1000 malformed requests and the server still answers; the patient list of the
// table; the token compared in constant time. The figures of a plan are checked against `pectus plan` in
// planner_page_browser_test.cc.
#include "apps/serve/planner_server.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "tests/apps/serve/test_server_options.h"
#include "tests/planner_plugin/host/analytic_chest.h"
#include "tests/planner_plugin/host/average_model_file.h"
#include "tests/support/require_shared_data.h"

// clang-format off
// Last: <resolv.h>, which httplib.h includes, defines _res, a name Eigen's headers use.
#include <httplib.h>
// clang-format on

namespace pectus::serve {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

class PlannerServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!testing_support::MissingSharedFile(testing_support::kPatientTable).empty()) return;
    dir_ = fs::temp_directory_path() / ("pectus_planner_server_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    planner::testing::WriteAverageModel(dir_ / "average.h5", planner::testing::AnalyticChestGrid(31, 41));
    PlannerServerOptions options =
        testing::TestServerOptions(testing_support::PatientTablePath(), dir_ / "average.h5");
    options.max_body_bytes = 64 * 1024;
    server_ = new PlannerServer(options);
    server_->Start();
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  void SetUp() override {
    PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
    ASSERT_NE(server_, nullptr);
  }
  static httplib::Client Client() {
    httplib::Client client("127.0.0.1", server_->port());
    client.set_connection_timeout(5);
    client.set_read_timeout(30);
    return client;
  }
  static httplib::Headers Token() { return {{"X-Pectus-Token", server_->token()}}; }
  // The status and the JSON error message of a response (empty if none).
  static std::string ErrorOf(const httplib::Result& r) {
    if (!r) return "(no response)";
    const json body = json::parse(r->body, nullptr, false);
    return body.is_object() && body.contains("error") ? body["error"].get<std::string>() : "";
  }
  // Sends `bytes` on a fresh connection and returns what came back (at most 4 KiB, 2 s); `hang_up`: closes
  // its sending side at once (the server sees the request end there).
  static std::string Raw(const std::string& bytes, bool hang_up = true) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(server_->port()));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    timeval timeout{2, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
    std::string reply;
    if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0) {
      (void)::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
      if (hang_up) ::shutdown(fd, SHUT_WR);
      char buffer[4096];
      ssize_t n = 0;
      while (reply.size() < 4096 && (n = ::recv(fd, buffer, sizeof(buffer), 0)) > 0)
        reply.append(buffer, static_cast<std::size_t>(n));
    }
    ::close(fd);
    return reply;
  }
  static inline PlannerServer* server_ = nullptr;
  static inline fs::path dir_;
};

TEST(ConstantTimeEqualsTest, EqualOnlyForTheSameBytes) {
  EXPECT_TRUE(ConstantTimeEquals("0123456789abcdef", "0123456789abcdef"));
  EXPECT_FALSE(ConstantTimeEquals("0123456789abcdef", "0123456789abcdeF"));
  EXPECT_FALSE(ConstantTimeEquals("0123456789abcdef", "0123456789abcde"));
  EXPECT_FALSE(ConstantTimeEquals("", "x"));
}

TEST(PlannerServerOptionsTest, FilesRequiredAndValuesInRange) {
  PlannerServerOptions o;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--patient-table"), std::string::npos);
  o.patient_table = "t.csv";
  o.model = "m.h5";
  EXPECT_TRUE(o.IsValid(&why)) << why;
  EXPECT_EQ(o.host, "127.0.0.1");  // loopback by default
  o.port = 70000;
  EXPECT_FALSE(o.IsValid(&why));
  o.port = 0;
  o.token = "short";
  EXPECT_FALSE(o.IsValid(&why));
}

TEST_F(PlannerServerTest, PrintsAUrlWithItsPortAndA32HexToken) {
  EXPECT_GT(server_->port(), 0);
  ASSERT_EQ(server_->token().size(), 32u);
  EXPECT_EQ(server_->token().find_first_not_of("0123456789abcdef"), std::string::npos);
  EXPECT_EQ(server_->url(),
            "http://127.0.0.1:" + std::to_string(server_->port()) + "/?token=" + server_->token());
}

TEST_F(PlannerServerTest, ListsEveryPatientOfTheTable) {
  auto client = Client();
  const auto r = client.Get("/api/patients", Token());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/json; charset=utf-8");
  const json list = json::parse(r->body);
  // The table: a header and one row per patient (62, Rechowicz 2012, Appendix A).
  std::ifstream in(testing_support::PatientTablePath());
  std::string line;
  int rows = -1;
  while (std::getline(in, line)) rows += !line.empty() && line[0] != '#';
  ASSERT_EQ(static_cast<int>(list.size()), rows);
  bool found = false;
  for (const json& p : list) found |= p["id"] == "57";
  EXPECT_TRUE(found);
}

// Answers go out uncompressed even to a browser that accepts brotli: cpp-httplib's brotli runs at its
// slowest setting (1.1 s for the page's script), and on the loopback nothing is gained.
TEST_F(PlannerServerTest, AnswersAreNotCompressedForABrowserThatAcceptsBrotli) {
  auto client = Client();
  client.set_decompress(false);
  httplib::Headers headers = Token();
  headers.emplace("Accept-Encoding", "gzip, deflate, br");
  const auto page = client.Get("/", Token());  // the page itself (small) may be compressed
  ASSERT_TRUE(page);
  ASSERT_EQ(page->status, 200);
  const auto at = page->body.find("/assets/");
  ASSERT_NE(at, std::string::npos) << page->body;
  const std::string script = page->body.substr(at, page->body.find('"', at) - at);
  for (const std::string& path : {std::string("/api/patients"), script}) {
    const auto r = client.Get(path, headers);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 200) << path;
    EXPECT_EQ(r->get_header_value("Content-Encoding"), "") << path;
    EXPECT_GT(r->body.size(), 1000u) << path;
  }
}

TEST_F(PlannerServerTest, WrongOrMissingTokenIs403) {
  auto client = Client();
  for (const httplib::Headers& headers :
       {httplib::Headers{}, httplib::Headers{{"X-Pectus-Token", std::string(32, '0')}},
        httplib::Headers{{"X-Pectus-Token", server_->token() + "0"}},
        httplib::Headers{{"Cookie", "pectus_token=" + std::string(32, 'a')}}}) {
    for (const char* path : {"/", "/index.html", "/api/patients", "/api/average"}) {
      const auto r = client.Get(path, headers);
      ASSERT_TRUE(r);
      EXPECT_EQ(r->status, 403) << path;
      EXPECT_FALSE(ErrorOf(r).empty()) << path;
    }
  }
  const auto post = client.Post("/api/plan", "{}", "application/json");
  ASSERT_TRUE(post);
  EXPECT_EQ(post->status, 403);
  // The token in the query, the header or the page's cookie passes.
  EXPECT_EQ(client.Get(("/api/patients?token=" + server_->token()).c_str())->status, 200);
  const auto page = client.Get(("/?token=" + server_->token()).c_str());
  ASSERT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<script"), std::string::npos);
  EXPECT_NE(page->get_header_value("Set-Cookie").find("HttpOnly; SameSite=Strict"), std::string::npos);
  EXPECT_EQ(client.Get("/api/average", {{"Cookie", "pectus_token=" + server_->token()}})->status, 200);
}

TEST_F(PlannerServerTest, ForeignHostIs403) {
  auto client = Client();
  const std::string port = std::to_string(server_->port());
  for (const std::string& host : std::vector<std::string>{"evil.example:" + port, "127.0.0.1", "localhost:1",
                                                          "127.0.0.1.evil.example:" + port}) {
    httplib::Headers headers = Token();
    headers.emplace("Host", host);
    const auto r = client.Get("/api/patients", headers);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 403) << host;
    EXPECT_NE(ErrorOf(r).find("Host"), std::string::npos) << host;
  }
  httplib::Headers local = Token();
  local.emplace("Host", "localhost:" + port);
  EXPECT_EQ(client.Get("/api/patients", local)->status, 200);
}

TEST_F(PlannerServerTest, PathTraversalIs404) {
  for (const std::string& path : std::vector<std::string>{
           "/../../../../etc/passwd", "/assets/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd",
           "/..%2f..%2fetc%2fpasswd", "/api/../../etc/passwd", "/etc/passwd", "/api/nothing"}) {
    const std::string reply =
        Raw("GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(server_->port()) +
                "\r\nX-Pectus-Token: " + server_->token() + "\r\nConnection: close\r\n\r\n",
            false);
    EXPECT_EQ(reply.substr(0, 12), "HTTP/1.1 404") << path << ": " << reply.substr(0, 200);
    EXPECT_EQ(reply.find("root:"), std::string::npos) << path;
    EXPECT_NE(reply.find("{\"error\":"), std::string::npos) << path;
  }
}

TEST_F(PlannerServerTest, OversizedBodyIs413) {
  auto client = Client();
  const std::string body(128 * 1024, ' ');  // twice the limit set above
  const auto r = client.Post("/api/plan", Token(), body, "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 413);
  EXPECT_EQ(ErrorOf(r), "request body too large");
}

TEST_F(PlannerServerTest, MalformedJsonIs400WithAMessage) {
  auto client = Client();
  // {route, body, what the message says}: the plan, then the live score, which checks its request the
  // same way before any work.
  const std::tuple<std::string, std::string, std::string> cases[] = {
      {"plan", "{bad", "malformed JSON"},
      {"plan", "", "malformed JSON"},
      {"plan", "[1, 2]", "must be a JSON object"},
      {"plan", R"({"bar": {"position": 0.85, "force_n": 200}})", "patient must be a string"},
      {"plan", R"({"patient": "57", "bar": {"position": 1.5, "force_n": 200}})",
       "bar.position = 1.5 is outside [0, 1]"},
      {"plan", R"({"patient": "57", "bar": {"position": 0.85, "force_n": "200"}})",
       "bar.force_n must be a number"},
      {"plan", R"({"patient": "57", "bar": {"position": 0.85, "force_n": -1}})",
       "bar.force_n = -1 is outside"},
      {"plan", R"({"patient": "57", "bar": {"position": 0.85, "force_n": 200, "position_in_mm": 3}})",
       "position_in_mm"},
      {"plan",
       R"({"patient": "57", "bar": {"position": 0.85, "force_n": 200}, "search": {"positions": 1000}})",
       "search.positions must be an integer in [2, 40]"},
      {"score", "{bad", "malformed JSON"},
      {"score", R"({"patient": "57"})", "bar must be an object"},
      {"score", R"({"patient": "57", "bar": {"position": 0.85, "force_n": 200}, "difference": 1})",
       "difference must be true or false"},
      {"score", R"({"patient": "57", "bar": {"position": 0.85, "force_n": 200}, "compare": {"position": 2}})",
       "compare.position = 2 is outside [0, 1]"},
      // The trainer's sessions: each request checked before any session or patient is looked up.
      {"trainer/start", "{bad", "malformed JSON"},
      {"trainer/start", R"({"introducer": "small"})", "patient must be a string"},
      {"trainer/start", R"({"patient": "57", "introducer": "huge"})", "introducer must be"},
      {"trainer/device", R"({"position": [0, 0, 0]})", "session must be a string"},
      {"trainer/device", R"({"session": "1", "position": [0, 0]})", "position must be [x, y, z]"},
      {"trainer/device", R"({"session": "1", "position": [0, 0, "a"]})", "three numbers"},
      {"trainer/device", R"({"session": "1", "position": [0, 0, 1e9]})", "within 2000 mm"},
      {"trainer/device", R"({"session": "1", "position": [0, 0, 0], "buttons": -1})",
       "device.buttons must be an integer in [0, 255]"},
      {"trainer/finish", R"({"session": 5})", "session must be a string"},
  };
  for (const auto& [route, body, message] : cases) {
    const auto r = client.Post("/api/" + route, Token(), body, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << route << " " << body << ": " << r->body;
    EXPECT_NE(ErrorOf(r).find(message), std::string::npos) << route << " " << body << ": " << r->body;
  }
  const auto unknown =
      client.Post("/api/plan", Token(),
                  R"({"patient": "no such", "bar": {"position": 0.85, "force_n": 200}})", "application/json");
  EXPECT_EQ(unknown->status, 404);
  EXPECT_NE(ErrorOf(unknown).find("no patient 'no such'"), std::string::npos);
  // A trainer session that was never started: 404 naming it, for every route that takes one.
  for (const auto& [route, body] :
       {std::pair<std::string, std::string>{"device", R"({"session": "999", "position": [0, 0, 0]})"},
        {"finish", R"({"session": "999"})"}}) {
    const auto r = client.Post("/api/trainer/" + route, Token(), body, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404) << route << ": " << r->body;
    EXPECT_NE(ErrorOf(r).find("no trainer session '999'"), std::string::npos) << r->body;
  }
  for (const std::string what : {"meshes", "record"}) {
    const auto r = client.Get("/api/trainer/999/" + what, Token());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404) << what << ": " << r->body;
  }
}

TEST_F(PlannerServerTest, AThousandMalformedRequestsAndTheServerStillAnswers) {
  auto client = Client();
  const std::string host = "Host: 127.0.0.1:" + std::to_string(server_->port()) + "\r\n";
  int answered = 0;
  for (int i = 0; i < 1000; ++i) {
    switch (i % 10) {
      case 0:  // garbage instead of HTTP
        Raw(std::string(static_cast<std::size_t>(1 + i % 97), static_cast<char>(i % 256)) + "\r\n\r\n");
        break;
      case 1:  // a request line without a version, then nothing
        Raw("GET /api/patients\r\n");
        break;
      case 2:  // a body shorter than its Content-Length (the server waits its read timeout at most)
        if (i % 100 == 2) Raw("POST /api/plan HTTP/1.1\r\n" + host + "Content-Length: 50\r\n\r\n{\"pat");
        break;
      case 3:  // a huge header
        Raw("GET / HTTP/1.1\r\n" + host + "X-A: " + std::string(20000, 'a') + "\r\n\r\n");
        break;
      default: {  // JSON that is not a plan, with the token
        const std::string body = i % 2 ? "{\"patient\": [" + std::to_string(i)
                                       : "{\"patient\": \"57\", \"bar\": " + std::to_string(i) + "}";
        const auto r = client.Post("/api/plan", Token(), body, "application/json");
        answered += r && r->status == 400;
      }
    }
  }
  EXPECT_EQ(answered, 600);
  const auto r = Client().Get("/api/patients", Token());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
}

}  // namespace
}  // namespace pectus::serve
