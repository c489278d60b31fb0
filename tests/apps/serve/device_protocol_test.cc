// The trainer's device protocol (apps/serve/device_protocol.h): the datagrams' layout both ways, bit for
// bit; bad datagrams refused; and a driver over UDP moving a session's device: its state becomes the device,
// the force and the proxy come back, wrong tokens and unknown or finished sessions are told apart.
#include "apps/serve/device_protocol.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "tests/apps/serve/test_server_options.h"
#include "tests/planner_plugin/host/analytic_chest.h"
#include "tests/planner_plugin/host/average_model_file.h"
#include "tests/support/require_shared_data.h"

// clang-format off
#include <httplib.h>
// clang-format on

namespace pectus::serve {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

TEST(DeviceProtocolTest, DatagramsReadBackBitForBitAndBadOnesAreRefused) {
  DeviceStateMessage state;
  state.token = "0123456789abcdef0123456789abcdef";
  state.session = 7;
  state.sequence = 4000000001u;
  state.position_mm[0] = -81.25;
  state.position_mm[1] = std::nextafter(12.5, 13.0);
  state.position_mm[2] = -160.0;
  state.orientation_wxyz[0] = std::sqrt(0.5);
  state.orientation_wxyz[2] = -std::sqrt(0.5);
  state.buttons = 0b101;
  const auto bytes = EncodeDeviceState(state);
  ASSERT_EQ(bytes.size(), 112u);
  EXPECT_EQ(std::memcmp(bytes.data(), "PDEV", 4), 0);
  DeviceStateMessage back;
  ASSERT_TRUE(DecodeDeviceState(bytes.data(), bytes.size(), &back));
  EXPECT_EQ(back.token, state.token);
  EXPECT_EQ(back.session, 7u);
  EXPECT_EQ(back.sequence, 4000000001u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(back.position_mm[k], state.position_mm[k]);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(back.orientation_wxyz[k], state.orientation_wxyz[k]);
  EXPECT_EQ(back.buttons, 0b101u);
  // The layout as the header documents it: the session at 40, x at 48 (little-endian).
  EXPECT_EQ(bytes[40], 7);
  double x;
  std::memcpy(&x, bytes.data() + 48, 8);
  EXPECT_EQ(x, -81.25);

  DeviceForceMessage force;
  force.session = 7;
  force.sequence = 9;
  force.force_n[1] = -0.3;
  force.torque_nmm[2] = 1.5;
  force.proxy_mm[0] = 3;
  force.organs = 2;
  force.status = kDeviceFinished;
  const auto reply = EncodeDeviceForce(force);
  DeviceForceMessage force_back;
  ASSERT_TRUE(DecodeDeviceForce(reply.data(), reply.size(), &force_back));
  EXPECT_EQ(std::memcmp(&force_back, &force, sizeof(force)), 0);

  // Wrong size, magic, version, a non-finite or far position, a zero quaternion: refused, the session and
  // the sequence still read (the answer names them).
  auto bad = bytes;
  EXPECT_FALSE(DecodeDeviceState(bad.data(), bad.size() - 1, &back));
  bad[0] = 'X';
  EXPECT_FALSE(DecodeDeviceState(bad.data(), bad.size(), &back));
  bad = bytes;
  bad[4] = 2;
  EXPECT_FALSE(DecodeDeviceState(bad.data(), bad.size(), &back));
  for (const double v : {std::nan(""), std::numeric_limits<double>::infinity(), 2500.0}) {
    DeviceStateMessage m = state;
    m.position_mm[1] = v;
    const auto b = EncodeDeviceState(m);
    EXPECT_FALSE(DecodeDeviceState(b.data(), b.size(), &back)) << v;
    EXPECT_EQ(back.sequence, state.sequence);
  }
  DeviceStateMessage zero = state;
  for (double& q : zero.orientation_wxyz) q = 0;
  const auto z = EncodeDeviceState(zero);
  EXPECT_FALSE(DecodeDeviceState(z.data(), z.size(), &back));
}

// Sends a state to the server's UDP port and waits for the answer (2 s at most).
DeviceForceMessage Exchange(int port, const DeviceStateMessage& state) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  timeval timeout{2, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const auto bytes = EncodeDeviceState(state);
  ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to));
  unsigned char buffer[256];
  const ssize_t n = ::recv(fd, buffer, sizeof(buffer), 0);
  ::close(fd);
  DeviceForceMessage out;
  out.status = 99;  // no answer
  if (n > 0) DecodeDeviceForce(buffer, static_cast<std::size_t>(n), &out);
  return out;
}

TEST(DeviceProtocolTest, ADriverOverUdpMovesTheSessionsDeviceAndGetsItsForce) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const fs::path dir = fs::temp_directory_path() / ("pectus_device_protocol_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  planner::testing::WriteAverageModel(dir / "average.h5", planner::testing::AnalyticChestGrid(31, 41));
  PlannerServerOptions options = testing::TestServerOptions(
      testing_support::SharedPath(testing_support::kPatientTable), dir / "average.h5");
  options.device_port = 0;
  PlannerServer server(options);
  server.Start();
  ASSERT_GT(server.device_port(), 0);
  httplib::Client client("127.0.0.1", server.port());
  client.set_read_timeout(120);
  const httplib::Headers token{{"X-Pectus-Token", server.token()}};
  const auto started = client.Post("/api/trainer/start", token, R"({"patient": "57"})", "application/json");
  ASSERT_TRUE(started);
  ASSERT_EQ(started->status, 200) << started->body;
  const json info = json::parse(started->body);
  const std::uint32_t session = std::stoul(info["session"].get<std::string>());

  DeviceStateMessage state;
  state.token = server.token();
  state.session = session;
  // The device 25 mm outside the entry port (free space: nothing there to touch), then 5 mm further out.
  Eigen::Vector3d p;
  for (int k = 0; k < 3; ++k) p[k] = info["start_mm"][k].get<double>();
  const Eigen::Vector3d entry(info["tunnel"]["entry_port_mm"][0].get<double>(),
                              info["tunnel"]["entry_port_mm"][1].get<double>(),
                              info["tunnel"]["entry_port_mm"][2].get<double>());
  p += 5.0 * (p - entry).normalized();
  for (int k = 0; k < 3; ++k) state.position_mm[k] = p[k];
  state.sequence = 1;
  DeviceForceMessage reply = Exchange(server.device_port(), state);
  EXPECT_EQ(reply.status, kDeviceOk);
  EXPECT_EQ(reply.session, session);
  EXPECT_EQ(reply.sequence, 1u);
  // A few servo ticks later the proxy is where the device is (free space), with no force.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  state.sequence = 2;
  reply = Exchange(server.device_port(), state);
  ASSERT_EQ(reply.status, kDeviceOk);
  EXPECT_EQ(reply.sequence, 2u);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(reply.proxy_mm[k], p[k], 1e-9) << k;
  EXPECT_EQ(reply.force_n[0], 0.0);
  EXPECT_EQ(reply.organs, 0u);
  // A wrong token, an unknown session, a malformed state: told apart.
  DeviceStateMessage wrong = state;
  wrong.token = std::string(32, '0');
  EXPECT_EQ(Exchange(server.device_port(), wrong).status, kDeviceWrongToken);
  DeviceStateMessage unknown = state;
  unknown.session = session + 100;
  EXPECT_EQ(Exchange(server.device_port(), unknown).status, kDeviceNoSession);
  DeviceStateMessage nan = state;
  nan.position_mm[0] = std::nan("");
  EXPECT_EQ(Exchange(server.device_port(), nan).status, kDeviceMalformed);
  // Finished: the driver is told so.
  const auto finished = client.Post("/api/trainer/finish", token,
                                    json{{"session", std::to_string(session)}}.dump(), "application/json");
  ASSERT_EQ(finished->status, 200) << finished->body;
  EXPECT_EQ(Exchange(server.device_port(), state).status, kDeviceFinished);
  // The session's record, asked for as a browser asks (brotli accepted): every tick of the report, sent
  // as it is (cpp-httplib would compress text with brotli at its slowest setting: 9 s for 28 000 ticks).
  const json report = json::parse(finished->body);
  client.set_decompress(false);
  httplib::Headers browser = token;
  browser.emplace("Accept-Encoding", "gzip, deflate, br");
  const auto record = client.Get(report["record"].get<std::string>(), browser);
  ASSERT_TRUE(record);
  ASSERT_EQ(record->status, 200) << record->body;
  EXPECT_EQ(record->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(record->get_header_value("Content-Type"), "text/plain; charset=utf-8");
  std::istringstream lines(record->body);
  int ticks = 0;
  for (std::string line; std::getline(lines, line);) ticks += line.rfind("tick ", 0) == 0;
  EXPECT_GT(ticks, 0);
  EXPECT_EQ(ticks, report["score"]["ticks"].get<int>()) << record->body.substr(0, 200);
  server.Stop();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pectus::serve
