// `penumbra view`: a live, side-by-side view of one technique against the progressive reference in
// the browser. A local HTTP server (cpp-httplib) bound to 127.0.0.1 only serves one self-contained
// page (view_page.html, compiled in) and the frames of a ViewSession (view_session.h):
//   GET  /            the page (no network resources: its Content-Security-Policy allows none)
//   GET  /api/setup   the scene, its lights and camera, every technique's parameter schema
//   POST /api/frame   one frame for the page's state (JSON); the reply is encodeViewFrame's bytes, or
//                     400 with the message (the schema's for a bad parameter value)
// Nothing else is served: every other path is 404, and a request whose Host is not this loopback
// address is refused (a web page elsewhere cannot reach the server through a name that resolves here).
// Frames are dropped, not queued: the page keeps one request in flight and sends only its newest
// state when the answer comes, and a request that finds a newer one waiting gives way to it (409).
// The server stops on Ctrl-C (SIGINT), SIGTERM and --max-seconds.
//
// `--measure-frames N` renders N frames per technique with the light moving every frame, without the
// server: the interactive path's pass times and frames per second (the README quotes them).
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <string_view>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "penumbra/error.h"
#include "view_session.h"

namespace penumbra::cli {

std::string_view viewPage();  // view_page.html, embedded by cmake/embed_page.cmake

namespace {

struct ViewOptions {
  FrameOptions frame;
  std::string technique = "pcss";
  int port = 0;
  std::optional<double> maxSeconds;
  uint32_t referenceSpp = 1024;
  std::string encoding = "raw";
  int measureFrames = 0;
  std::vector<std::string> measureTechniques = {"hard", "pcf", "pcss", "brabec", "plm"};
};

std::string errorJson(const std::string& message) { return nlohmann::json{{"error", message}}.dump(); }

// Blocks SIGINT and SIGTERM in this thread and the threads it starts (the server's), so that the
// watcher alone receives them; the old mask comes back at the end.
class BlockedStopSignals {
 public:
  BlockedStopSignals() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set_, &old_);
  }
  ~BlockedStopSignals() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  const sigset_t& set() const { return set_; }

 private:
  sigset_t set_{}, old_{};
};

int serve(const ViewOptions& options, const Setup& setupInfo, ViewSession& session) {
  const std::string setup = session.setupJson(options.technique, options.frame.lightIndex);
  httplib::Server server;
  std::mutex renderMutex;
  std::atomic<uint64_t> latestTicket{0};
  int port = 0;

  // Only this loopback address, under the names a local browser uses for it.
  const auto hostAllowed = [&](const httplib::Request& request) {
    const std::string host = request.get_header_value("Host");
    return host == fmt::format("127.0.0.1:{}", port) || host == fmt::format("localhost:{}", port);
  };
  server.set_pre_routing_handler([&](const httplib::Request& request, httplib::Response& response) {
    if (hostAllowed(request)) return httplib::Server::HandlerResponse::Unhandled;
    response.status = 403;
    response.set_content(errorJson("refused: this server answers only requests addressed to 127.0.0.1"),
                         "application/json");
    return httplib::Server::HandlerResponse::Handled;
  });
  server.Get("/", [&](const httplib::Request&, httplib::Response& response) {
    // The page must not reach the network: no resource outside itself and this server.
    response.set_header("Content-Security-Policy",
                        "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                        "img-src data: blob:; connect-src 'self'");
    response.set_header("Cache-Control", "no-store");
    response.set_content(std::string(viewPage()), "text/html; charset=utf-8");
  });
  server.Get("/api/setup", [&](const httplib::Request&, httplib::Response& response) {
    response.set_header("Cache-Control", "no-store");
    response.set_content(setup, "application/json");
  });
  server.Post("/api/frame", [&](const httplib::Request& request, httplib::Response& response) {
    const uint64_t ticket = ++latestTicket;
    std::lock_guard lock(renderMutex);
    if (ticket != latestTicket.load()) {
      response.status = 409;
      response.set_content(errorJson("dropped: a newer frame was asked for"), "application/json");
      return;
    }
    try {
      const ViewRequest parsed = session.parseRequest(request.body);
      response.set_content(encodeViewFrame(session.render(parsed)), "application/octet-stream");
      response.set_header("Cache-Control", "no-store");
    } catch (const Error& e) {
      response.status = 400;
      response.set_content(errorJson(e.what()), "application/json");
    } catch (const std::bad_alloc&) {
      response.status = 500;
      response.set_content(errorJson("out of memory (try a smaller --width/--height)"), "application/json");
    } catch (const std::exception& e) {
      response.status = 500;
      response.set_content(errorJson(fmt::format("internal: {}", e.what())), "application/json");
    }
  });
  server.set_error_handler([](const httplib::Request& request, httplib::Response& response) {
    if (response.status == 404)
      response.set_content(
          errorJson(fmt::format("not found: {} (this server has /, /api/setup and /api/frame)", request.path)),
          "application/json");
  });

  // SO_REUSEADDR alone: a restart may take the port back from a closed connection at once, but a port
  // another server listens on stays refused (cpp-httplib's default, SO_REUSEPORT, would share it).
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  const BlockedStopSignals blocked;
  port = options.port == 0 ? server.bind_to_any_port("127.0.0.1")
                           : (server.bind_to_port("127.0.0.1", options.port) ? options.port : -1);
  if (port <= 0)
    fail("--port {}: cannot listen on 127.0.0.1:{} (in use? choose another, or 0 for any free port)", options.port,
         options.port);
  fmt::print("penumbra view: {}\nopen http://127.0.0.1:{}/ in a browser (Ctrl-C stops the server)\n",
             describeSetup(setupInfo), port);
  std::fflush(stdout);

  std::atomic<bool> finished{false};
  std::string why;
  std::thread watcher([&] {
    const auto start = std::chrono::steady_clock::now();
    const timespec poll{0, 100'000'000};
    while (!finished.load()) {
      const int signal = sigtimedwait(&blocked.set(), nullptr, &poll);
      if (signal == SIGINT || signal == SIGTERM) {
        why = signal == SIGINT ? "Ctrl-C" : "SIGTERM";
        break;
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (options.maxSeconds && seconds >= *options.maxSeconds) {
        why = fmt::format("--max-seconds {:g}", *options.maxSeconds);
        break;
      }
    }
    server.stop();
  });
  const bool listened = server.listen_after_bind();
  finished = true;
  server.stop();
  watcher.join();
  fmt::print("penumbra view: stopped ({})\n", why.empty() ? "server ended" : why);
  return listened || !why.empty() ? 0 : 1;
}

// The interactive path without the server: the light moves along a small circle every frame, so each
// frame prepares the technique again and restarts the reference (one batch), as a drag does.
int measure(const ViewOptions& options, const Setup& setup, ViewSession& session) {
  fmt::print("penumbra view --measure-frames {}: {}\n", options.measureFrames, describeSetup(setup));
  fmt::print("steady frames (the first of each technique builds its G-buffer and caches and is left out), median ms\n");
  fmt::print("{:<12} {:>8} {:>8} {:>10} {:>9} {:>8} {:>8} {:>8} {:>10} {:>10}\n", "technique", "gbuffer", "prepare",
             "visibility", "reference", "metrics", "encode", "frame", "frame fps", "shadow fps");
  const float radius = 0.05f * session.scene().bounds().radius();
  for (const std::string& name : options.measureTechniques) {
    ViewRequest request = session.initialRequest(name, options.frame.lightIndex);
    const Vec3 start = request.lightPosition;
    std::map<std::string, std::vector<double>> passes;
    std::vector<double> frames, shadows;
    std::optional<std::string> failed;
    for (int k = 0; k <= options.measureFrames; ++k) {
      const float angle = 6.2831853f * static_cast<float>(k) / static_cast<float>(std::max(options.measureFrames, 1));
      request.lightPosition = start + radius * Vec3(std::cos(angle), 0.0f, std::sin(angle));
      const ViewFrame frame = session.render(request);
      if (frame.techniqueError) failed = *frame.techniqueError;
      if (k == 0) continue;
      double total = 0.0;
      for (const auto& [pass, ms] : frame.passMs) {
        passes[pass].push_back(ms);
        total += ms;
      }
      frames.push_back(total);
      shadows.push_back(passes["prepare"].back() + passes["visibility"].back());
    }
    if (failed) {
      fmt::print("{:<12} not run here: {}\n", name, *failed);
      continue;
    }
    const double frame = median(frames), shadow = median(shadows);
    fmt::print("{:<12} {:>8.2f} {:>8.2f} {:>10.2f} {:>9.2f} {:>8.2f} {:>8.2f} {:>8.2f} {:>10.1f} {:>10.1f}\n", name,
               median(passes["gbuffer"]), median(passes["prepare"]), median(passes["visibility"]),
               median(passes["reference"]), median(passes["metrics"]), median(passes["encode"]), frame, 1000.0 / frame,
               1000.0 / shadow);
  }
  return 0;
}

int runView(const ViewOptions& options) {
  ThreadLimit threads(options.frame.threads);
  const Setup setup = loadSetup(options.frame);
  const TechniqueInfo& info = findTechnique(options.technique);
  if (info.name == "reference")
    fail("--technique reference: the reference is the other side of the view; choose a technique");
  for (const std::string& name : options.measureTechniques) findTechnique(name);
  ViewSession::Options sessionOptions;
  sessionOptions.width = setup.width;
  sessionOptions.height = setup.height;
  sessionOptions.referenceMaxSpp = options.referenceSpp;
  sessionOptions.encoding = options.encoding == "png" ? FrameEncoding::Png : FrameEncoding::Raw;
  ViewSession session(setup.scene, sessionOptions);
  // The first frame's checks (the light, the technique's parameters from the scene file) before serving.
  ViewRequest first = session.initialRequest(info.name, setup.lightIndex);
  if (const auto it = setup.scene.techniqueParams.find(info.name); it != setup.scene.techniqueParams.end())
    resolveParams(info.name, info.params, it->second);
  session.makeLight(first);
  if (options.measureFrames > 0) return measure(options, setup, session);
  return serve(options, setup, session);
}

}  // namespace

Command addViewCommand(CLI::App& parent) {
  auto options = std::make_shared<ViewOptions>();
  options->frame.width = 512;
  options->frame.height = 512;
  CLI::App* app = parent.add_subcommand(
      "view", "a live view in the browser: one technique beside the progressive reference, light and camera movable");
  app->add_option("--scene", options->frame.scene,
                  "built-in scene name (see `penumbra scenes`) or path to a JSON scene file")
      ->capture_default_str();
  app->add_option("--light", options->frame.lightIndex, "index of the scene's light to start from")
      ->capture_default_str();
  app->add_option("--width", options->frame.width, "image width in pixels")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app->add_option("--height", options->frame.height, "image height in pixels")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app->add_option("--technique,-t", options->technique, "technique shown first (see `penumbra techniques`)")
      ->capture_default_str();
  app->add_option("--port", options->port, "port on 127.0.0.1 (0: any free port; the URL is printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  app->add_option("--max-seconds", options->maxSeconds,
                  "stop the server after this many seconds (default: run until Ctrl-C)")
      ->check(CLI::PositiveNumber);
  app->add_option("--reference-spp", options->referenceSpp,
                  "samples per pixel the progressive reference accumulates to while the view is still")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  app->add_option("--encoding", options->encoding,
                  "how frames travel to the page: raw 8-bit pixels, or PNG files (slower to encode)")
      ->check(CLI::IsMember({"raw", "png"}))
      ->capture_default_str();
  app->add_option("--measure-frames", options->measureFrames,
                  "no server: time this many frames of each --measure technique with the light moving, and print "
                  "the pass times and frames per second")
      ->check(CLI::Range(1, 100000));
  app->add_option("--measure", options->measureTechniques, "the techniques --measure-frames times")
      ->delimiter(',')
      ->capture_default_str();
  app->add_option("--threads", options->frame.threads, "worker threads (0: every core)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app->add_option("--max-mesh-size", options->frame.maxMeshMiB, "largest mesh file imported, MiB")
      ->check(CLI::PositiveNumber);
  return {app, [options] { return runView(*options); }};
}

}  // namespace penumbra::cli
