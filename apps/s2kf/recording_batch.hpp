/// @file
/// Many recordings in one `s2kf track` run: the recordings a command line names (files, folders
/// searched at any depth), the part of them one shard takes, their output prefixes, and the
/// threads that track them, one recording each, so that a failure stays with its recording.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace s2kf::cli {

/// A recording to track and the name of its outputs: its path below the folder it was found in,
/// without the extension ("S01/Walk01"), or its file name for a file given as such.
struct Recording {
  std::string input;
  std::string name;
};

/// The recordings of the command line: every .c3d file in a folder, at any depth, named by its path
/// below that folder (so outputs mirror the folders and same-named takes of different subjects
/// stay apart), and every file given as such, named after itself. Sorted by name: the order
/// --shard deals out, the same on every machine wherever the data are mounted.
std::vector<Recording> find_recordings(const std::vector<std::string>& inputs);

/// --shard I/N: the recordings whose place in the sorted list is I modulo N (I from 0 to N-1), so N
/// runs with I = 0..N-1 track every recording exactly once, in parts that differ by one at most.
std::vector<Recording> shard_of(const std::vector<Recording>& recordings, const std::string& shard);

/// The output prefix of each recording: `out`/name when `out_is_folder` (a batch, or --out naming
/// a folder), else `out` itself, or the recording's name when `out` is empty.
std::vector<std::string> output_prefixes(const std::vector<Recording>& recordings, const std::string& out,
                                         bool out_is_folder);

/// Tracks every recording with `track_one(index)` (which returns the paragraph to print) on `jobs`
/// threads, largest files first. A recording that fails is reported on stderr in one line that
/// names it, and its PREFIX.json records the error (s2kf summarize lists it); the others go on.
/// Throws UserError naming the failed recordings when any failed.
void track_in_batch(const std::vector<Recording>& recordings, const std::vector<std::string>& prefixes,
                    unsigned jobs, bool quiet, const std::function<std::string(std::size_t)>& track_one);

}  // namespace s2kf::cli
