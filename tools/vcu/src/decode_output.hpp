#pragma once
// The output of `vcu dbc decode` and `vcu dump`'s numbers: the one frame writer of
// shared/trace (openvcu/trace/frame_writer.hpp), named in openvcu::cli for the commands.

#include "openvcu/trace/frame_writer.hpp"

namespace openvcu::cli {

using trace::appendCsvField;
using trace::appendJsonString;
using trace::appendNumber;
using trace::appendRaw;
using trace::appendSeconds;
using trace::DecodeFormat;
using trace::FrameWriter;
using trace::SignalValue;

}  // namespace openvcu::cli
