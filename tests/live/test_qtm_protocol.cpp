// The QTM protocol's packets and parameter XML: byte layouts written out by hand from the
// protocol's documentation, round trips, and every malformed input a clear ProtocolError.
#include <s2kf/live/qtm_protocol.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace {

using namespace s2kf::live;

void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) b.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}
void putf(std::vector<std::uint8_t>& b, float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put32(b, bits);
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "no error";
}

TEST(QtmProtocol, HeaderIsSizeThenTypeLittleEndian) {
  const std::vector<std::uint8_t> packet = text_packet(PacketType::command, "Bye");
  // 8 header bytes + "Bye" + NUL = 12 = 0x0c; type 1.
  const std::vector<std::uint8_t> expected{0x0c, 0, 0, 0, 1, 0, 0, 0, 'B', 'y', 'e', 0};
  EXPECT_EQ(packet, expected);
  const PacketHeader header = parse_header(packet.data(), packet.size());
  EXPECT_EQ(header.size, 12u);
  EXPECT_EQ(header.type, PacketType::command);
  EXPECT_EQ(packet_text(packet.data() + 8, header.body_bytes()), "Bye");
}

TEST(QtmProtocol, MalformedHeadersAreErrors) {
  const std::uint8_t short_header[5] = {12, 0, 0, 0, 1};
  EXPECT_NE(error_of([&] { parse_header(short_header, 5); }).find("truncated packet header: 5 of its 8"),
            std::string::npos);
  const std::uint8_t too_small[8] = {4, 0, 0, 0, 1, 0, 0, 0};
  EXPECT_NE(error_of([&] { parse_header(too_small, 8); }).find("declares 4 bytes, fewer than"),
            std::string::npos);
  const std::uint8_t too_big[8] = {0xff, 0xff, 0xff, 0x7f, 3, 0, 0, 0};
  EXPECT_NE(error_of([&] { parse_header(too_big, 8); }).find("more than the"), std::string::npos);
  const std::uint8_t unknown[8] = {8, 0, 0, 0, 9, 0, 0, 0};
  EXPECT_NE(error_of([&] { parse_header(unknown, 8); }).find("unknown packet type 9"), std::string::npos);
  const std::uint8_t no_more_data[8] = {8, 0, 0, 0, 4, 0, 0, 0};
  EXPECT_EQ(parse_header(no_more_data, 8).type, PacketType::no_more_data);
  EXPECT_EQ(no_more_data_packet(), std::vector<std::uint8_t>(no_more_data, no_more_data + 8));
}

/// A data packet as the protocol documents it, written byte by byte: a 2D component first (skipped),
/// then the 3D one with two markers, the second missing (NaN).
std::vector<std::uint8_t> hand_made_data_packet() {
  std::vector<std::uint8_t> body;
  put32(body, 123456789);  // timestamp, low word
  put32(body, 0);          // timestamp, high word
  put32(body, 42);         // frame number
  put32(body, 2);          // component count
  put32(body, 12);         // component 1: size
  put32(body, 7);          // type 2D
  put32(body, 0);          // no cameras
  put32(body, 16 + 24);    // component 2: size
  put32(body, 1);          // type 3D
  put32(body, 2);          // markers
  body.push_back(0);
  body.push_back(0);  // 2D drop rate
  body.push_back(0);
  body.push_back(0);  // out of sync rate
  putf(body, 1.5f);
  putf(body, -2.25f);
  putf(body, 1000.f);
  for (int k = 0; k < 3; ++k) putf(body, std::nanf(""));
  std::vector<std::uint8_t> packet;
  put32(packet, static_cast<std::uint32_t>(8 + body.size()));
  put32(packet, 3);
  packet.insert(packet.end(), body.begin(), body.end());
  return packet;
}

TEST(QtmProtocol, DataPacketAsDocumented) {
  const std::vector<std::uint8_t> packet = hand_made_data_packet();
  const PacketHeader header = parse_header(packet.data(), packet.size());
  ASSERT_EQ(header.type, PacketType::data);
  Frame3d frame;
  parse_data_body(packet.data() + 8, header.body_bytes(), frame);
  EXPECT_EQ(frame.timestamp_us, 123456789u);
  EXPECT_EQ(frame.frame_number, 42u);
  ASSERT_TRUE(frame.has_3d);
  ASSERT_EQ(frame.positions.cols(), 2);
  EXPECT_EQ(frame.positions(0, 0), 1.5);
  EXPECT_EQ(frame.positions(1, 0), -2.25);
  EXPECT_EQ(frame.positions(2, 0), 1000.0);
  EXPECT_TRUE(frame.visible(0));
  EXPECT_FALSE(frame.visible(1));
  EXPECT_TRUE(std::isnan(frame.positions(0, 1)));
}

TEST(QtmProtocol, DataPacketRoundTrip) {
  Eigen::Matrix3Xd positions(3, 3);
  positions << 1, 2, 3, 4, 5, 6, 7, 8, 9.125;
  s2kf::FrameVisibility visible(3);
  visible << true, false, true;
  const std::vector<std::uint8_t> packet = data_packet_3d(7, 99, positions, visible);
  EXPECT_EQ(packet.size(), 8u + 16 + 16 + 3 * 12);
  Frame3d frame;
  parse_data_body(packet.data() + 8, packet.size() - 8, frame);
  EXPECT_EQ(frame.frame_number, 7u);
  EXPECT_EQ(frame.timestamp_us, 99u);
  EXPECT_EQ(frame.visible(0), true);
  EXPECT_EQ(frame.visible(1), false);
  EXPECT_EQ(frame.positions(2, 2), 9.125);
  EXPECT_EQ(frame.positions.col(0), positions.col(0));
}

TEST(QtmProtocol, DataPacketsThatLieAreErrors) {
  std::vector<std::uint8_t> packet = hand_made_data_packet();
  Frame3d frame;
  const auto body_error = [&](const std::vector<std::uint8_t>& p) {
    return error_of([&] { parse_data_body(p.data() + 8, p.size() - 8, frame); });
  };
  std::vector<std::uint8_t> more_markers = packet;
  more_markers[8 + 16 + 12 + 8] = 200;  // 200 markers in a component of 40 bytes
  EXPECT_NE(body_error(more_markers).find("declares 200 markers, but its 40 bytes hold at most 2"),
            std::string::npos);
  std::vector<std::uint8_t> long_component = packet;
  long_component[8 + 16 + 12] = 0xf0;  // the 3D component claims 240 bytes
  EXPECT_NE(body_error(long_component).find("declares 240 bytes, but 40 remain"), std::string::npos);
  std::vector<std::uint8_t> more_components = packet;
  more_components[8 + 12] = 3;
  EXPECT_NE(body_error(more_components).find("component 3 of 3 begins past the packet's end"),
            std::string::npos);
  const std::vector<std::uint8_t> short_body(packet.begin(), packet.begin() + 8 + 10);
  EXPECT_NE(body_error(short_body).find("too short"), std::string::npos);
}

const char* kQtmLikeXml = R"(<?xml version="1.0"?>
<QTM_Parameters_Ver_1.25>
  <General>
    <Frequency>150</Frequency>
    <Capture_Time>10.000000</Capture_Time>
    <External_Timestamp><Enabled>false</Enabled><Frequency>999</Frequency></External_Timestamp>
  </General>
  <!-- a comment <Label> -->
  <The_3D>
    <AxisUpwards>+Z</AxisUpwards>
    <CalibrationTime>2019-09-17 16:00:43</CalibrationTime>
    <Labels>3</Labels>
    <Label><Name>LFHD</Name><RGBColor>2124031</RGBColor><Trajectory_Type>Measured</Trajectory_Type></Label>
    <Label>
      <Name> R&amp;FHD </Name>
      <RGBColor>2124031</RGBColor>
    </Label>
    <Label><Name>C7</Name><Color R="0" G="255" B="0"/></Label>
    <Bones/>
  </The_3D>
</QTM_Parameters_Ver_1.25>
)";

TEST(QtmProtocol, ParametersXmlAsQtmWritesIt) {
  const StreamParameters parameters = parse_parameters_xml(kQtmLikeXml);
  EXPECT_EQ(parameters.rate_hz, 150.0);
  EXPECT_EQ(parameters.labels, (std::vector<std::string>{"LFHD", "R&FHD", "C7"}));
}

TEST(QtmProtocol, ParametersXmlRoundTrip) {
  const StreamParameters written{{"LASI", "<odd & name>", "RASI"}, 120.5};
  const StreamParameters read = parse_parameters_xml(parameters_xml(written));
  EXPECT_EQ(read.labels, written.labels);
  EXPECT_EQ(read.rate_hz, 120.5);
}

TEST(QtmProtocol, BadParametersXmlIsAnError) {
  const auto error = [](const std::string& xml) { return error_of([&] { parse_parameters_xml(xml); }); };
  EXPECT_NE(error("<Q><General><Frequency>100</Frequency></General></Q>").find("no <The_3D>"),
            std::string::npos);
  EXPECT_NE(error("<Q><The_3D><Labels>0</Labels></The_3D></Q>").find("no <General><Frequency>"),
            std::string::npos);
  EXPECT_NE(error("<Q><General><Frequency>-3</Frequency></General><The_3D/></Q>").find("not a positive"),
            std::string::npos);
  EXPECT_NE(error("<Q><General><Frequency>100</Frequency></General><The_3D><Labels>2</Labels>"
                  "<Label><Name>A</Name></Label></The_3D></Q>")
                .find("announce 2 labels but list 1"),
            std::string::npos);
  EXPECT_NE(error("<Q><General><Frequency>100</General></Q>").find("<Q> is not closed"), std::string::npos);
  EXPECT_NE(error("<Q><General><Frequency>100</Frequency></Q></General>").find("closes </General> where <Q>"),
            std::string::npos);
  EXPECT_NE(error("<Q><The_3D>").find("not closed"), std::string::npos);
  EXPECT_NE(error("<Q></Q><R></R>").find("2 root elements"), std::string::npos);
  EXPECT_NE(error("<Q><The_3D></Q").find("tag is not closed"), std::string::npos);
}

}  // namespace
