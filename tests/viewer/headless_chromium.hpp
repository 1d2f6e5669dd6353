/// @file
/// Running Debian's chromium headless on a local page from a test: the DOM after the page's scripts
/// ran (--dump-dom), a screenshot, and the console output; and why chromium cannot run here, when it
/// cannot, so the test can say so and skip.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace s2kf::test_support {

struct ChromiumRun {
  int status = -1;
  std::string stdout_text;  ///< the DOM with --dump-dom
  std::string stderr_text;  ///< chromium's log, with the page's console messages (CONSOLE lines)
};

inline std::string chromium_path() {
  if (const char* given = std::getenv("S2KF_CHROMIUM")) return given;
  for (const char* candidate : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
    if (std::filesystem::exists(candidate)) return candidate;
  return {};
}

inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Runs chromium headless on `url` with `mode` ("--dump-dom" or "--screenshot=FILE"). The flags
/// keep it offline and quiet (no sync, updates, QUIC or background requests) and give WebGL a
/// software rasteriser (SwiftShader), which headless machines without a GPU need.
inline ChromiumRun run_chromium(const std::string& url, const std::string& mode,
                                const std::filesystem::path& work) {
  namespace fs = std::filesystem;
  static int run = 0;
  const fs::path profile =
      work / ("chromium_profile_" + std::to_string(::getpid()) + "_" + std::to_string(run++));
  fs::remove_all(profile);
  fs::create_directories(profile);
  const fs::path out = profile / "stdout.txt", err = profile / "stderr.txt";
  const std::string command =
      "timeout 90 \"" + chromium_path() +
      "\" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking"
      " --disable-component-update --disable-sync --use-angle=swiftshader --enable-unsafe-swiftshader"
      " --hide-scrollbars --window-size=1280,720 --enable-logging=stderr --v=0 --virtual-time-budget=8000"
      " --user-data-dir=\"" +
      profile.string() + "\" " + mode + " \"" + url + "\" > \"" + out.string() + "\" 2> \"" + err.string() +
      "\"";
  const int raw = std::system(command.c_str());
  ChromiumRun result;
  result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  result.stdout_text = slurp(out);
  result.stderr_text = slurp(err);
  fs::remove_all(profile);
  return result;
}

/// Empty when chromium can render a trivial page here, else the reason it cannot.
inline std::string chromium_unavailable_reason(const std::filesystem::path& work) {
  const std::string path = chromium_path();
  if (path.empty())
    return "no chromium found (/usr/bin/chromium; Debian: apt-get install chromium, or set S2KF_CHROMIUM)";
  namespace fs = std::filesystem;
  fs::create_directories(work);
  const fs::path probe = work / "chromium_probe.html";
  std::ofstream(probe)
      << "<!doctype html><p id=probe></p><script>document.getElementById('probe').textContent="
         "'ran'</script>";
  const ChromiumRun run = run_chromium("file://" + fs::absolute(probe).string(), "--dump-dom", work);
  if (run.stdout_text.find("<p id=\"probe\">ran</p>") == std::string::npos)
    return path + " does not run headless here (exit status " + std::to_string(run.status) +
           "): " + run.stderr_text.substr(0, 400);
  return {};
}

}  // namespace s2kf::test_support
