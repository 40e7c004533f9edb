// fsm::readReloadFile (issue 18): a reload reads only a regular file of bounded size inside
// the configuration's folders; every refusal names the path and the reason, never the
// file's content, and nothing blocks (FIFO, device).

#include <doctest/doctest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "reload_file.hpp"
#include "reload_worker.hpp"
#include "shared/fsm/fsm_test_support.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

constexpr const char* SECRET = "hunter2-do-not-show";
constexpr const char* MACHINE = R"({"initialState": "A", "states": [{"name": "A", "transitions": []}]})";
constexpr std::size_t SMALL_LIMIT = 1000;
constexpr auto QUICK = std::chrono::milliseconds(500);

/// A fresh folder tree: <root>/config (allowed) with fsm.json, <root>/outside with a 0600 secret.
struct Folders {
  fs::path root;
  fs::path config;
  fs::path outside;

  Folders() {
    std::string pattern = (fs::temp_directory_path() / "openvcu-reload-XXXXXX").string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    root = pattern;
    config = root / "config";
    outside = root / "outside";
    fs::create_directories(config);
    fs::create_directories(outside);
    write(config / "fsm.json", MACHINE);
    write(outside / "secret.json", std::string(R"({"initialState": ")") + SECRET + R"(", "states": []})");
    fs::permissions(outside / "secret.json", fs::perms::owner_read | fs::perms::owner_write);
  }
  ~Folders() {
    std::error_code ignored;
    fs::remove_all(root, ignored);
  }
  Folders(const Folders&) = delete;
  Folders& operator=(const Folders&) = delete;

  static void write(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    REQUIRE(out.good());
  }
  [[nodiscard]] std::vector<std::string> allowed() const { return {config.string()}; }
  [[nodiscard]] Result<std::string> read(const std::string& path, std::size_t limit = fsm::RELOAD_MAX_BYTES) const {
    return fsm::readReloadFile(path, allowed(), limit);
  }
};

/// Refused with "PATH: ...REASON..." and without the secret.
template <typename T>
void requireRefused(const Result<T>& result, const std::string& path, const std::string& reason) {
  REQUIRE_FALSE(result);
  const std::string& message = result.error().message;
  INFO(message);
  CHECK(message.starts_with(path + ": "));
  CHECK(message.find(reason) != std::string::npos);
  CHECK(message.find(SECRET) == std::string::npos);
}

template <typename Call>
auto timed(Call call, std::chrono::milliseconds* took) {
  const auto start = std::chrono::steady_clock::now();
  auto result = call();
  *took = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start);
  return result;
}

}  // namespace

TEST_CASE("a regular file inside the configuration folder is read whole") {
  const Folders folders;
  const auto result = folders.read((folders.config / "fsm.json").string());
  REQUIRE_MESSAGE(result, (result ? "" : result.error().message));
  CHECK(*result == MACHINE);
}

TEST_CASE("a 0600 file outside the folders is refused without its content, and so is a missing one") {
  const Folders folders;
  const std::string secret = (folders.outside / "secret.json").string();
  const auto result = folders.read(secret);
  requireRefused(result, secret, "outside the folders a reload may read (" + folders.config.string() + ")");
  // Whether a file exists outside is not told either: the same reason for a missing one.
  const std::string missing = (folders.outside / "missing.json").string();
  const auto absent = folders.read(missing);
  requireRefused(absent, missing, "outside the folders a reload may read");
  CHECK(absent.error().message.substr(missing.size()) == result.error().message.substr(secret.size()));
}

TEST_CASE("a FIFO inside the folder is refused at once, without blocking") {
  const Folders folders;
  const fs::path fifo = folders.config / "fifo.json";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  std::chrono::milliseconds took{};
  const auto result = timed([&] { return folders.read(fifo.string()); }, &took);
  requireRefused(result, fifo.string(), "not a regular file");
  CHECK(took < QUICK);
}

TEST_CASE("/dev/zero is refused: outside the folders, through a symlink, and as a device in an allowed /dev") {
  const Folders folders;
  requireRefused(folders.read("/dev/zero"), "/dev/zero", "outside the folders");
  const fs::path link = folders.config / "zero.json";
  fs::create_symlink("/dev/zero", link);
  requireRefused(folders.read(link.string()), link.string(), "outside the folders a reload may read (" +
                                                                 folders.config.string() + ") after resolving symlinks");
  std::chrono::milliseconds took{};
  const auto device = timed([] { return fsm::readReloadFile("/dev/zero", {"/dev"}, fsm::RELOAD_MAX_BYTES); }, &took);
  requireRefused(device, "/dev/zero", "not a regular file");
  CHECK(took < QUICK);
}

TEST_CASE("a directory is refused") {
  const Folders folders;
  fs::create_directories(folders.config / "sub.json");
  requireRefused(folders.read((folders.config / "sub.json").string()), (folders.config / "sub.json").string(),
                 "a directory, not a regular file");
  requireRefused(folders.read(folders.config.string()), folders.config.string(), "a directory");
}

TEST_CASE("a symlink escaping the folder is refused, for a file and for a directory") {
  const Folders folders;
  const fs::path fileLink = folders.config / "link.json";
  fs::create_symlink(folders.outside / "secret.json", fileLink);
  requireRefused(folders.read(fileLink.string()), fileLink.string(), "after resolving symlinks");
  const fs::path directoryLink = folders.config / "elsewhere";
  fs::create_directory_symlink(folders.outside, directoryLink);
  const std::string through = (directoryLink / "secret.json").string();
  requireRefused(folders.read(through), through, "after resolving symlinks");
  // A missing file behind it gives the same answer (no existence test through the link).
  const std::string missing = (directoryLink / "missing.json").string();
  requireRefused(folders.read(missing), missing, "after resolving symlinks");
  // A symlink that stays inside is fine.
  const fs::path inner = folders.config / "current.json";
  fs::create_symlink(folders.config / "fsm.json", inner);
  const auto result = folders.read(inner.string());
  REQUIRE_MESSAGE(result, (result ? "" : result.error().message));
  CHECK(*result == MACHINE);
}

TEST_CASE("a path climbing out with .. is refused, and .. after a symlinked directory stays lexical") {
  const Folders folders;
  const std::string climbing = folders.config.string() + "/../outside/secret.json";
  requireRefused(folders.read(climbing), climbing, "outside the folders a reload may read");
  // config/elsewhere -> outside/sub: "config/elsewhere/../secret.json" means config/secret.json,
  // never outside/secret.json.
  fs::create_directories(folders.outside / "sub");
  fs::create_directory_symlink(folders.outside / "sub", folders.config / "elsewhere");
  const std::string viaLink = (folders.config / "elsewhere").string() + "/../secret.json";
  requireRefused(folders.read(viaLink), viaLink, "cannot open: No such file or directory");
  const std::string inside = folders.config.string() + "/sub/../fsm.json";
  const auto result = folders.read(inside);
  REQUIRE_MESSAGE(result, (result ? "" : result.error().message));
}

TEST_CASE("a file over the size limit is refused with both sizes") {
  const Folders folders;
  const fs::path big = folders.config / "big.json";
  Folders::write(big, std::string(SMALL_LIMIT + 1, ' '));
  requireRefused(folders.read(big.string(), SMALL_LIMIT), big.string(),
                 "too large: " + std::to_string(SMALL_LIMIT + 1) + " bytes (at most " + std::to_string(SMALL_LIMIT) + ")");
  Folders::write(big, std::string(SMALL_LIMIT, ' '));
  CHECK(folders.read(big.string(), SMALL_LIMIT));
}

TEST_CASE("a relative, empty or missing path is refused with the reason") {
  const Folders folders;
  requireRefused(folders.read("fsm.json"), "fsm.json", "not an absolute path");
  requireRefused(folders.read(""), "(empty path)", "not an absolute path");
  const std::string missing = (folders.config / "missing.json").string();
  requireRefused(folders.read(missing), missing, "cannot open: No such file or directory");
}

TEST_CASE("the reload folders are the FSM file's folder and the vehicle configuration's folder") {
  config::VehicleConfig vehicle;
  vehicle.directory = "/etc/openvcu/hhea";
  vehicle.fsmFile = "/srv/fsm/v2/fsm.json";
  CHECK(fsm::reloadFolders(vehicle) == std::vector<std::string>{"/srv/fsm/v2", "/etc/openvcu/hhea"});
  vehicle.fsmFile = "/etc/openvcu/hhea/fsm.json";
  CHECK(fsm::reloadFolders(vehicle) == std::vector<std::string>{"/etc/openvcu/hhea"});
}

TEST_CASE("loadReloadMachine: a file with errors is refused with its path and error count, never its content") {
  const Folders folders;
  const fsmtest::Hhea hhea;
  const fs::path leaky = folders.config / "leaky.json";
  Folders::write(leaky, std::string(R"({"initialState": ")") + SECRET + R"(", "states": [{"name": "A"}]})");
  fs::permissions(leaky, fs::perms::owner_read | fs::perms::owner_write);
  std::vector<Error> diagnostics;
  const auto result = fsm::loadReloadMachine(leaky.string(), folders.allowed(), hhea.vehicle, hhea.catalog, &diagnostics);
  requireRefused(result, leaky.string(), "1 error; details in vcu-fsm's log or from `vcu fsm check " + leaky.string() + "`");
  // the diagnostics (for the local log only) do say what is wrong
  REQUIRE_FALSE(diagnostics.empty());
  CHECK(diagnostics.front().message.find(SECRET) != std::string::npos);

  const fs::path broken = folders.config / "broken.json";
  Folders::write(broken, "{\n  \"initialState\": \"A\",\n  \"states\": [,]\n}");
  requireRefused(fsm::loadReloadMachine(broken.string(), folders.allowed(), hhea.vehicle, hhea.catalog, nullptr),
                 broken.string(), "1 error (the first at line 3)");

  const auto good = fsm::loadReloadMachine((folders.config / "fsm.json").string(), folders.allowed(), hhea.vehicle,
                                           hhea.catalog, nullptr);
  REQUIRE_MESSAGE(good, (good ? "" : good.error().message));
  CHECK(good->states.size() == 1);
  // outside the folders: readReloadFile's refusal
  requireRefused(fsm::loadReloadMachine((folders.outside / "secret.json").string(), folders.allowed(), hhea.vehicle,
                                        hhea.catalog, nullptr),
                 (folders.outside / "secret.json").string(), "outside the folders");
}

TEST_CASE("the reload worker loads on its own thread and reports when it finished") {
  std::mutex mutex;
  std::condition_variable done;
  bool finished = false;
  std::thread::id loadedOn;
  fsm::ReloadWorker sut(
      [&](const std::string& path) -> Result<fsm::Machine> {
        loadedOn = std::this_thread::get_id();
        return Error{path + ": refused for the test"};
      },
      [&] {
        std::lock_guard lock(mutex);
        finished = true;
        done.notify_all();
      });
  CHECK_FALSE(sut.take());
  sut.start("/x/fsm.json");
  {
    std::unique_lock lock(mutex);
    REQUIRE(done.wait_for(lock, std::chrono::seconds(5), [&] { return finished; }));
  }
  auto result = sut.take();
  REQUIRE(result);
  REQUIRE_FALSE(*result);
  CHECK(result->error().message == "/x/fsm.json: refused for the test");
  CHECK(loadedOn != std::this_thread::get_id());
  CHECK_FALSE(sut.take());  // once
}
