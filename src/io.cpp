// The compiled copy of the definitions in s2kf/io/ (core/compilation_mode.hpp).
#include <s2kf/io/bvh.hxx>
#include <s2kf/io/c3d_reader.hxx>
#include <s2kf/io/c3d_writer.hxx>
#include <s2kf/io/mmm_motion.hxx>
#include <s2kf/io/motion_derivatives.hxx>
#include <s2kf/io/motion_files.hxx>
#include <s2kf/io/motion_stream_writer.hxx>
#include <s2kf/io/opensim_model.hxx>
#include <s2kf/io/sample_cache.hxx>
#include <s2kf/io/trc_file.hxx>
