// Tests of `penumbra view` (apps/penumbra/view.cpp, view_session.h): the session's frames against a
// technique run directly and against the reference, the progressive reference (it grows while still,
// restarts when the light moves, stops at its limit, and approaches a long reference), the schema's
// message for a bad parameter value, a technique that cannot take the light costing only its side; and
// the server as a user's browser meets it, through the real binary: loopback only, nothing but its
// page and API served, bad requests answered with a message, stopped by --max-seconds or SIGTERM.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "view_session.h"

namespace penumbra::cli {
namespace {

constexpr int kSize = 64;

ViewSession makeSession(uint32_t referenceSpp = 126, const std::string& scene = "crowded") {
  ViewSession::Options options;
  options.width = options.height = kSize;
  options.referenceMaxSpp = referenceSpp;
  return ViewSession(loadScene(scene), options);
}

nlohmann::json frameHeader(const std::string& bytes) {
  EXPECT_GE(bytes.size(), 4u);
  uint32_t length = 0;
  for (int b = 0; b < 4; ++b) length |= static_cast<uint32_t>(static_cast<uint8_t>(bytes[b])) << (8 * b);
  return nlohmann::json::parse(bytes.substr(4, length));
}

TEST(ViewSession, TheTechniqueSideIsTheTechniquesOwnV) {
  ViewSession session = makeSession();
  const ViewRequest request = session.initialRequest("pcss", 0);
  const ViewFrame frame = session.render(request);
  ASSERT_TRUE(frame.technique.has_value());
  EXPECT_FALSE(frame.techniqueError.has_value());

  // The same technique on the same G-buffer and light, run directly.
  const Scene scene = loadScene("crowded");
  const GBuffer gbuffer = renderGBuffer(scene, kSize, kSize);
  std::unique_ptr<ShadowTechnique> pcss = createTechnique("pcss");
  pcss->prepare(scene, scene.lights[0]);
  Image<float> v;
  pcss->visibility(gbuffer, v);
  EXPECT_EQ(frame.technique->bytes, grayBytes(v));
  EXPECT_EQ(frame.technique->channels, 1);
  EXPECT_FALSE(frame.technique->png);
  // The scene's own light, as the file gives it.
  const Light light = session.makeLight(request);
  EXPECT_EQ(light.center(), scene.lights[0].center());
  EXPECT_EQ(light.radius(), scene.lights[0].radius());
}

TEST(ViewSession, TheReferenceAccumulatesWhileStillAndRestartsWhenTheLightMoves) {
  ViewSession session = makeSession(126);
  ViewRequest request = session.initialRequest("hard", 0);
  std::vector<uint32_t> samples;
  std::vector<double> errors;
  for (int k = 0; k < 7; ++k) {
    const ViewFrame frame = session.render(request);
    samples.push_back(frame.referenceSamples);
    errors.push_back(frame.referenceStdError);
    EXPECT_EQ(frame.gbufferCached, k > 0);
    EXPECT_EQ(frame.techniqueCached, k > 0);  // nothing it depends on changed
  }
  EXPECT_EQ(samples, (std::vector<uint32_t>{2, 6, 14, 30, 62, 126, 126}));
  for (size_t k = 1; k < 6; ++k) EXPECT_LT(errors[k], errors[k - 1]) << "batch " << k;

  request.lightPosition += Vec3(0.2f, 0.0f, 0.0f);
  const ViewFrame moved = session.render(request);
  EXPECT_EQ(moved.referenceSamples, 2u);
  EXPECT_TRUE(moved.gbufferCached);
  EXPECT_FALSE(moved.techniqueCached);
}

TEST(ViewSession, TheProgressiveReferenceApproachesALongOne) {
  ViewSession session = makeSession(510);
  const ViewRequest request = session.initialRequest("hard", 0);
  ViewFrame frame;
  for (int k = 0; k < 20 && frame.referenceSamples < 510; ++k) frame = session.render(request);
  ASSERT_EQ(frame.referenceSamples, 510u);

  const Scene scene = loadScene("crowded");
  const GBuffer gbuffer = renderGBuffer(scene, kSize, kSize);
  ReferenceOptions options;
  options.samplesPerPixel = 4096;
  auto reference = makeTechnique(options);
  reference->prepare(scene, scene.lights[0]);
  Image<float> truth;
  reference->visibility(gbuffer, truth);
  // The reference side in V bytes against the long reference: within a few of its own standard errors.
  const std::vector<uint8_t> bytes = frame.reference.bytes;
  ASSERT_EQ(bytes.size(), truth.size());
  double sum = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) sum += std::pow(bytes[i] / 255.0 - truth[i], 2.0);
  const double rmse = std::sqrt(sum / static_cast<double>(truth.size()));
  EXPECT_LT(rmse, 3.0 * frame.referenceStdError + 0.5 / 255.0) << "mean standard error " << frame.referenceStdError;
  EXPECT_GT(frame.referenceStdError, 0.0);
}

TEST(ViewSession, ABadParameterValueGetsTheSchemasMessage) {
  ViewSession session = makeSession();
  ViewRequest request = session.initialRequest("pcss", 0);
  request.params["map_size"] = "3";
  try {
    session.render(request);
    FAIL() << "a map_size of 3 was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pcss.map_size = 3 is not valid: expected"), std::string::npos) << e.what();
  }
  request.params = {{"no_such", "1"}};
  EXPECT_THROW(session.render(request), Error);
  request.params.clear();
  request.technique = "no-such-technique";
  EXPECT_THROW(session.render(request), Error);
  // The session goes on after a refusal.
  request.technique = "pcss";
  EXPECT_TRUE(session.render(request).technique.has_value());
}

TEST(ViewSession, ATechniqueThatCannotTakeTheLightCostsOnlyItsSide) {
  ViewSession session = makeSession();
  const ViewRequest request = session.initialRequest("heidrich", 0);  // segment lights only; crowded's is a sphere
  const ViewFrame frame = session.render(request);
  EXPECT_FALSE(frame.technique.has_value());
  ASSERT_TRUE(frame.techniqueError.has_value());
  EXPECT_NE(frame.techniqueError->find("heidrich"), std::string::npos) << *frame.techniqueError;
  EXPECT_EQ(frame.reference.bytes.size(), static_cast<size_t>(kSize * kSize));
  EXPECT_FALSE(frame.error.has_value());
  const nlohmann::json header = frameHeader(encodeViewFrame(frame));
  EXPECT_EQ(header["images"].size(), 1u);
  EXPECT_TRUE(header["techniqueError"].is_string());
}

TEST(ViewSession, EveryLightShapeAndDisplay) {
  ViewSession session = makeSession(2);
  ViewRequest request = session.initialRequest("pcss", 0);
  for (const LightShape shape : {LightShape::Sphere, LightShape::Disk, LightShape::Rect, LightShape::Directional}) {
    request.shape = shape;
    request.lightSize = shape == LightShape::Directional ? 2.0f : 0.5f;
    for (const ViewDisplay display : {ViewDisplay::Visibility, ViewDisplay::Shaded, ViewDisplay::Error}) {
      request.display = display;
      const ViewFrame frame = session.render(request);
      ASSERT_TRUE(frame.technique.has_value()) << toString(shape) << ": " << frame.techniqueError.value_or("");
      const int channels = display == ViewDisplay::Visibility ? 1 : 3;
      EXPECT_EQ(frame.technique->channels, channels);
      EXPECT_EQ(frame.technique->bytes.size(), static_cast<size_t>(kSize * kSize * channels));
      // The frame's bytes: the header, then each image where the header says.
      const std::string bytes = encodeViewFrame(frame);
      const nlohmann::json header = frameHeader(bytes);
      size_t total = 0;
      for (const auto& image : header["images"]) total += image["length"].get<size_t>();
      uint32_t length = 0;
      for (int b = 0; b < 4; ++b) length |= static_cast<uint32_t>(static_cast<uint8_t>(bytes[b])) << (8 * b);
      EXPECT_EQ(bytes.size(), 4 + length + total);
    }
  }
  request.shape = LightShape::Polygon;  // crowded's light is a sphere: no polygon to keep
  EXPECT_THROW(session.render(request), Error);
  request.shape = LightShape::Sphere;
  request.lightSize = -1.0f;
  EXPECT_THROW(session.render(request), Error);
}

TEST(ViewSession, PngFramesDecodeToTheRawOnes) {
  ViewSession::Options options;
  options.width = options.height = kSize;
  options.referenceMaxSpp = 2;
  options.encoding = FrameEncoding::Png;
  ViewSession session(loadScene("crowded"), options);
  const ViewFrame frame = session.render(session.initialRequest("hard", 0));
  ASSERT_TRUE(frame.technique.has_value());
  EXPECT_TRUE(frame.technique->png);
  int width = 0, height = 0, channels = 0;
  const ViewImage& png = *frame.technique;
  stbi_uc* pixels =
      stbi_load_from_memory(png.bytes.data(), static_cast<int>(png.bytes.size()), &width, &height, &channels, 0);
  ASSERT_NE(pixels, nullptr);
  EXPECT_EQ(width, kSize);
  EXPECT_EQ(height, kSize);
  EXPECT_EQ(channels, 1);
  // The same pixels as a raw frame of the same request.
  ViewSession raw = makeSession(2);
  const ViewFrame rawFrame = raw.render(raw.initialRequest("hard", 0));
  EXPECT_EQ(std::vector<uint8_t>(pixels, pixels + kSize * kSize), rawFrame.technique->bytes);
  stbi_image_free(pixels);
}

TEST(ViewSession, RequestsAreCheckedFieldByField) {
  const ViewSession session = makeSession();
  const auto message = [&](const std::string& json) {
    try {
      session.parseRequest(json);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string camera = R"("camera": {"position": [0, 3, 8], "lookAt": [0, 0, 0], "up": [0, 1, 0], "fovY": 45})";
  const std::string light = R"("light": {"index": 0, "shape": "disk", "position": [0, 5, 0], "size": 0.5})";
  EXPECT_EQ(message("{" + camera + "," + light + R"(, "technique": "hard", "display": "v"})"), "accepted");
  EXPECT_NE(message("not json").find("request: not JSON"), std::string::npos);
  EXPECT_NE(message("{" + light + R"(, "technique": "hard", "display": "v"})").find("request.camera"),
            std::string::npos);
  EXPECT_NE(message("{" + camera + R"(, "light": {"index": 7, "shape": "disk", "position": [0, 5, 0], "size": 1},
                     "technique": "hard", "display": "v"})")
                .find("request.light.index"),
            std::string::npos);
  EXPECT_NE(message("{" + camera + R"(, "light": {"index": 0, "shape": "blob", "position": [0, 5, 0], "size": 1},
                     "technique": "hard", "display": "v"})")
                .find("request.light.shape: 'blob'"),
            std::string::npos);
  EXPECT_NE(message("{" + camera + R"(, "light": {"index": 0, "shape": "disk", "position": [0, 5], "size": 1},
                     "technique": "hard", "display": "v"})")
                .find("request.light.position"),
            std::string::npos);
  EXPECT_NE(message("{" + camera + "," + light + R"(, "technique": "hard", "display": "x"})").find("request.display"),
            std::string::npos);
  EXPECT_NE(message("{" + camera + "," + light + R"(, "technique": "hard", "params": {"a": [1]}, "display": "v"})")
                .find("request.params.a"),
            std::string::npos);
}

// `penumbra view ARGS` started with its output on a pipe, read up to the line with its URL.
struct RunningView {
  pid_t pid = -1;
  FILE* pipe = nullptr;  //!< the program's stdout and stderr
  int port = 0;
  std::string output;

  // Starts `penumbra view` with `args` (words separated by single spaces) and reads its output up to
  // the URL it serves.
  explicit RunningView(const std::string& args) {
    std::vector<std::string> words = {PENUMBRA_CLI, "view"};
    for (size_t start = 0; start < args.size();) {
      const size_t end = std::min(args.find(' ', start), args.size());
      if (end > start) words.push_back(args.substr(start, end - start));
      start = end + 1;
    }
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);
    int fds[2];
    if (::pipe(fds) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn_file_actions_addclose(&actions, fds[1]);
    const int spawned = posix_spawn(&pid, PENUMBRA_CLI, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    pipe = fdopen(fds[0], "r");
    if (spawned != 0) {
      pid = -1;
      return;
    }
    char line[4096];
    while (pipe && port == 0 && std::fgets(line, sizeof line, pipe)) {
      output += line;
      std::smatch m;
      const std::string text = line;
      if (std::regex_search(text, m, std::regex(R"(http://127\.0\.0\.1:(\d+)/)"))) port = std::stoi(m[1]);
    }
  }
  RunningView(const RunningView&) = delete;
  RunningView& operator=(const RunningView&) = delete;
  // Reads the rest of the output and waits for the program to end; its wait status.
  int finish() {
    char line[4096];
    while (pipe && std::fgets(line, sizeof line, pipe)) output += line;
    if (pipe) std::fclose(pipe);
    pipe = nullptr;
    int status = -1;
    if (pid > 0) waitpid(pid, &status, 0);
    pid = -1;
    return status;
  }
  // Asks the server to stop (SIGTERM, as a terminal's Ctrl-C would) before its --max-seconds, then
  // finish().
  int stop() {
    if (pid > 0) ::kill(pid, SIGTERM);
    return finish();
  }
  // A test that ends early (a failed assertion) does not wait out --max-seconds.
  ~RunningView() { stop(); }
};

// The binary's server, as a browser meets it.
TEST(ViewServer, ServesOnlyItsPageAndApiOnLoopbackAndStops) {
  RunningView view("--scene crowded --width 48 --height 48 --port 0 --max-seconds 6 --threads 2");
  ASSERT_GT(view.port, 0) << view.output;
  const int port = view.port;

  httplib::Client client("127.0.0.1", port);
  const auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'none'"), std::string::npos);
  EXPECT_EQ(page->body.find("http://"), std::string::npos) << "the page names no outside resource";
  EXPECT_EQ(page->body.find("https://"), std::string::npos) << "the page names no outside resource";
  const auto setup = client.Get("/api/setup");
  ASSERT_TRUE(setup);
  EXPECT_EQ(nlohmann::json::parse(setup->body)["scene"], "crowded");

  for (const char* path :
       {"/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/view_page.html", "/api/frame", "/api/../CMakeLists.txt"}) {
    const auto refused = client.Get(path);
    ASSERT_TRUE(refused) << path;
    EXPECT_EQ(refused->status, 404) << path;
    EXPECT_EQ(refused->body.find("root:"), std::string::npos) << path;
  }
  const auto foreignHost = client.Get("/", {{"Host", "attacker.example"}});
  ASSERT_TRUE(foreignHost);
  EXPECT_EQ(foreignHost->status, 403);
  const auto badJson = client.Post("/api/frame", "{not json", "application/json");
  ASSERT_TRUE(badJson);
  EXPECT_EQ(badJson->status, 400);
  EXPECT_NE(nlohmann::json::parse(badJson->body)["error"].get<std::string>().find("request: not JSON"),
            std::string::npos);
  const std::string frameRequest =
      R"({"camera": {"position": [0, 8, 10], "lookAt": [0, 0.5, 0], "up": [0, 1, 0], "fovY": 45},
          "light": {"index": 0, "shape": "sphere", "position": [0.5, 8, -1], "size": 0.8},
          "technique": "pcss", "params": {"blocker_samples": "0"}, "display": "v"})";
  const auto badValue = client.Post("/api/frame", frameRequest, "application/json");
  ASSERT_TRUE(badValue);
  EXPECT_EQ(badValue->status, 400);
  EXPECT_NE(badValue->body.find("blocker_samples"), std::string::npos) << badValue->body;
  std::string good = frameRequest;
  good.replace(good.find(R"({"blocker_samples": "0"})"), 24, "{}");
  const auto frame = client.Post("/api/frame", good, "application/json");
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->status, 200);
  EXPECT_EQ(frameHeader(frame->body)["images"].size(), 2u);

  const int status = view.finish();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << view.output;
  EXPECT_NE(view.output.find("stopped (--max-seconds 6)"), std::string::npos) << view.output;
}

// Three requests at once: the first renders; of the two waiting, the older gives way to the newer.
TEST(ViewServer, ARequestWaitingBehindANewerOneIsDropped) {
  // --max-seconds only bounds a server that hangs: the test stops it once the answers are in.
  RunningView view("--scene crowded --width 2048 --height 2048 --port 0 --max-seconds 120");
  ASSERT_GT(view.port, 0) << view.output;
  const int port = view.port;
  const std::string request =
      R"({"camera": {"position": [0, 8, 10], "lookAt": [0, 0.5, 0], "up": [0, 1, 0], "fovY": 45},
          "light": {"index": 0, "shape": "sphere", "position": [0.5, 8, -1], "size": 0.8},
          "technique": "raytraced-soft", "params": {"spp": 16, "skip_uniform_tiles": false}, "display": "v"})";
  // The first frame (a G-buffer of 4M pixels and 16 shadow rays for each, mostly Embree's work, which
  // the sanitizer build does not instrument) takes far longer than the 1.2 s the third request waits,
  // in either build; the third leaves 800 ms after the second, a margin that a client thread or the
  // server's handler slowed by a busy machine (the tests run side by side) does not eat, where 100 ms
  // once did. The later two ask for the same frame, which the first leaves cached: they cost little.
  // Not a frame of many shadow maps: every pixel reads texels of all of them, which miss the caches,
  // and the sanitizer's check of each can stretch the frame past the test's time limit.
  int status[3] = {0, 0, 0};
  std::vector<std::thread> clients;
  for (int k = 0; k < 3; ++k)
    clients.emplace_back([&, k] {
      std::this_thread::sleep_for(std::chrono::milliseconds(k == 0 ? 0 : k == 1 ? 400 : 1200));
      httplib::Client client("127.0.0.1", port);
      client.set_read_timeout(std::chrono::seconds(110));
      if (const auto response = client.Post("/api/frame", request, "application/json")) status[k] = response->status;
    });
  for (std::thread& t : clients) t.join();
  EXPECT_EQ(status[0], 200);
  EXPECT_EQ(status[1], 409) << "the second request was rendered although a newer one waited";
  EXPECT_EQ(status[2], 200);
  const int exit = view.stop();
  EXPECT_TRUE(WIFEXITED(exit) && WEXITSTATUS(exit) == 0) << view.output;
}

TEST(ViewServer, ABusyPortIsRefusedByName) {
  httplib::Server holder;
  const int port = holder.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  RunningView view("--scene torus --port " + std::to_string(port) + " --max-seconds 2");
  const int status = view.finish();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << view.output;
  EXPECT_NE(view.output.find(fmt::format("--port {}: cannot listen on 127.0.0.1:{}", port, port)), std::string::npos)
      << view.output;
}

}  // namespace
}  // namespace penumbra::cli
