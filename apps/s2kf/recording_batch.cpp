#include "recording_batch.hpp"

#include "front_end.hpp"

#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_error.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <numeric>
#include <thread>
#include <tuple>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

bool is_c3d_file(const fs::directory_entry& entry) {
  std::string ext = entry.path().extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".c3d" && entry.is_regular_file();
}

/// An error of one recording in a batch as one line that starts with the recording's path.
std::string error_naming_file(const std::string& input, const std::exception& error) {
  if (const auto* c3d_error = dynamic_cast<const c3d::C3dError*>(&error))
    return input + ": " + c3d_error->sentence();
  const std::string what = error.what();
  return what.rfind(input, 0) == 0 ? what : input + ": " + what;
}

/// In place of the summary of a recording that failed in a batch: PREFIX.json with its error, which
/// s2kf summarize lists. Outputs an earlier run left under the prefix stay as they were.
void record_failure(const std::string& input, const std::string& prefix, const std::string& error) {
  const nlohmann::json record = {{"input", input}, {"status", "failed"}, {"error", error}};
  io::write_file_atomically(prefix + ".json", [&](std::ostream& out) { out << record.dump(2) << "\n"; });
}

}  // namespace

std::vector<Recording> find_recordings(const std::vector<std::string>& inputs) {
  std::vector<Recording> recordings;
  for (const std::string& input : inputs) {
    if (fs::is_directory(input)) {
      std::size_t found = 0;
      for (const auto& entry :
           fs::recursive_directory_iterator(input, fs::directory_options::skip_permission_denied))
        if (is_c3d_file(entry)) {
          recordings.push_back({entry.path().string(),
                                entry.path().lexically_relative(input).replace_extension().generic_string()});
          ++found;
        }
      if (found == 0)
        throw UserError(input + " is a folder without .c3d files (its subfolders searched too)");
    } else if (!fs::exists(input)) {
      throw UserError(input + ": no such file");
    } else {
      recordings.push_back({input, fs::path(input).stem().string()});
    }
  }
  std::sort(recordings.begin(), recordings.end(), [](const Recording& a, const Recording& b) {
    return std::tie(a.name, a.input) < std::tie(b.name, b.input);
  });
  return recordings;
}

std::vector<Recording> shard_of(const std::vector<Recording>& recordings, const std::string& shard) {
  const auto slash = shard.find('/');
  const auto whole_number = [](const std::string& text) {
    return !text.empty() && text.size() <= 9 && text.find_first_not_of("0123456789") == std::string::npos;
  };
  if (slash == std::string::npos || !whole_number(shard.substr(0, slash)) ||
      !whole_number(shard.substr(slash + 1)))
    throw UserError("--shard " + shard + ": expected I/N with whole numbers 0 <= I < N, e.g. --shard 0/8");
  const std::size_t index = std::stoul(shard.substr(0, slash)), count = std::stoul(shard.substr(slash + 1));
  if (count == 0 || index >= count)
    throw UserError("--shard " + shard + ": I counts from 0 and must be smaller than N (the shards of N = " +
                    std::to_string(count) + " are 0/" + std::to_string(count) + " to " +
                    std::to_string(count == 0 ? 0 : count - 1) + "/" + std::to_string(count) + ")");
  std::vector<Recording> part;
  for (std::size_t k = index; k < recordings.size(); k += count) part.push_back(recordings[k]);
  return part;
}

std::vector<std::string> output_prefixes(const std::vector<Recording>& recordings, const std::string& out,
                                         bool out_is_folder) {
  std::vector<std::string> prefixes;
  for (const Recording& recording : recordings)
    prefixes.push_back(out_is_folder ? (fs::path(out.empty() ? "." : out) / recording.name).string()
                       : out.empty() ? recording.name
                                     : out);
  return prefixes;
}

void track_in_batch(const std::vector<Recording>& recordings, const std::vector<std::string>& prefixes,
                    unsigned jobs, bool quiet, const std::function<std::string(std::size_t)>& track_one) {
  // Largest files first: a long recording started last would leave the other threads idle at the
  // end. (Were times proportional to sizes, longest-first would stay within 4/3 of the best order.)
  std::vector<std::uintmax_t> bytes;
  for (const Recording& recording : recordings) {
    std::error_code error;
    const std::uintmax_t size = fs::file_size(recording.input, error);
    bytes.push_back(error ? 0 : size);
  }
  std::vector<std::size_t> order(recordings.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return bytes[a] > bytes[b]; });
  std::atomic<std::size_t> next{0};
  std::mutex print;
  std::vector<std::string> failures;
  auto worker = [&]() {
    for (std::size_t n; (n = next++) < recordings.size();) {
      const std::size_t i = order[n];
      const std::string& input = recordings[i].input;
      try {
        fs::create_directories(fs::path(prefixes[i]).parent_path());
        const std::string paragraph = track_one(i);
        std::lock_guard<std::mutex> lock(print);
        if (!quiet) std::cout << paragraph << "\n\n" << std::flush;
      } catch (const std::exception& e) {
        const std::string message = error_naming_file(input, e);
        std::string unrecorded;
        try {
          record_failure(input, prefixes[i], message);
        } catch (const std::exception& f) {
          unrecorded = error_naming_file(input, f);
        }
        std::lock_guard<std::mutex> lock(print);
        failures.push_back(input);
        std::cerr << "s2kf: " << message << "\n";
        if (!unrecorded.empty()) std::cerr << "s2kf: " << unrecorded << "\n";
      }
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < std::min<std::size_t>(jobs, recordings.size()); ++t) threads.emplace_back(worker);
  for (auto& thread : threads) thread.join();
  if (failures.empty()) return;
  std::sort(failures.begin(), failures.end());
  constexpr std::size_t kNamed = 10;  // a failure list longer than this ends in "and N more"
  std::string list;
  for (std::size_t i = 0; i < std::min(kNamed, failures.size()); ++i) list += (i ? ", " : "") + failures[i];
  if (failures.size() > kNamed) list += " and " + std::to_string(failures.size() - kNamed) + " more";
  throw UserError(std::to_string(failures.size()) + " of " + std::to_string(recordings.size()) +
                  " recordings could not be tracked: " + list +
                  " (errors above and in each one's .json; the others were tracked)");
}

}  // namespace s2kf::cli
