// Protobuf delimited framing on byte vectors: split, coalesced, oversize, malformed.
#include <gtest/gtest.h>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include "inspect_robot/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"

using inspect::net::DelimitedDecoder;
using inspect::net::appendDelimited;
using Status = DelimitedDecoder::Status;

namespace {
inspect::v1::Envelope telemetry(int i) {
  inspect::v1::Envelope e;
  e.set_seq(static_cast<uint64_t>(i));
  auto* t = e.mutable_telemetry();
  t->mutable_pose()->set_x_m(i * 0.5);
  for (int k = 0; k < 4; ++k) t->add_ultrasonic_m(k + i);
  return e;
}

std::vector<inspect::v1::Envelope> drain(DelimitedDecoder& d) {
  std::vector<inspect::v1::Envelope> out;
  std::span<const uint8_t> f;
  while (d.next(f) == Status::kFrame) {
    inspect::v1::Envelope e;
    EXPECT_TRUE(DelimitedDecoder::parse(f, e));
    out.push_back(e);
  }
  return out;
}
}  // namespace

TEST(Delimited, CoalescedFramesInOneRead) {
  std::string wire;
  for (int i = 1; i <= 5; ++i) ASSERT_TRUE(appendDelimited(telemetry(i), wire));
  DelimitedDecoder d;
  d.append(wire.data(), wire.size());
  const auto got = drain(d);
  ASSERT_EQ(got.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(got[i].seq(), static_cast<uint64_t>(i + 1));
  EXPECT_EQ(d.buffered(), 0u);
}

TEST(Delimited, ByteByByte) {
  std::string wire;
  for (int i = 1; i <= 3; ++i) appendDelimited(telemetry(i), wire);
  DelimitedDecoder d;
  std::vector<inspect::v1::Envelope> got;
  for (char c : wire) {
    d.append(&c, 1);
    for (auto& e : drain(d)) got.push_back(e);
  }
  ASSERT_EQ(got.size(), 3u);
  EXPECT_DOUBLE_EQ(got[2].telemetry().pose().x_m(), 1.5);
}

TEST(Delimited, InteroperatesWithProtobufsOwnDelimitedReader) {
  std::string wire;
  appendDelimited(telemetry(7), wire);
  google::protobuf::io::ArrayInputStream ais(wire.data(), static_cast<int>(wire.size()));
  google::protobuf::io::CodedInputStream cis(&ais);
  uint32_t len = 0;
  ASSERT_TRUE(cis.ReadVarint32(&len));
  auto limit = cis.PushLimit(static_cast<int>(len));
  inspect::v1::Envelope e;
  ASSERT_TRUE(e.ParseFromCodedStream(&cis));
  cis.PopLimit(limit);
  EXPECT_EQ(e.seq(), 7u);
}

TEST(Delimited, OversizeLengthIsRejectedBeforeAllocating) {
  DelimitedDecoder d(1024);
  // Varint for 1 GiB followed by nothing: must be refused at once, not awaited.
  const std::vector<uint8_t> hdr = {0x80, 0x80, 0x80, 0x80, 0x04};
  d.append(hdr);
  std::span<const uint8_t> f;
  EXPECT_EQ(d.next(f), Status::kInvalid);
  EXPECT_NE(d.error().find("exceeds the maximum"), std::string::npos);
  EXPECT_EQ(d.next(f), Status::kInvalid) << "stays invalid";
}

TEST(Delimited, OverlongVarintIsInvalid) {
  DelimitedDecoder d;
  const std::vector<uint8_t> hdr(12, 0xFF);
  d.append(hdr);
  std::span<const uint8_t> f;
  EXPECT_EQ(d.next(f), Status::kInvalid);
}

TEST(Delimited, TruncatedFrameWaits) {
  std::string wire;
  appendDelimited(telemetry(1), wire);
  DelimitedDecoder d;
  d.append(wire.data(), wire.size() - 1);
  std::span<const uint8_t> f;
  EXPECT_EQ(d.next(f), Status::kNeedMore);
  d.append(wire.data() + wire.size() - 1, 1);
  EXPECT_EQ(d.next(f), Status::kFrame);
}

TEST(Delimited, GarbageBodyFailsToParse) {
  const std::vector<uint8_t> wire = {0x03, 0xFF, 0xFF, 0xFF};
  DelimitedDecoder d;
  d.append(wire);
  std::span<const uint8_t> f;
  ASSERT_EQ(d.next(f), Status::kFrame);
  inspect::v1::Envelope e;
  EXPECT_FALSE(DelimitedDecoder::parse(f, e));
}

TEST(Delimited, ZeroLengthFrameIsAnEmptyEnvelope) {
  const std::vector<uint8_t> wire = {0x00};
  DelimitedDecoder d;
  d.append(wire);
  std::span<const uint8_t> f;
  ASSERT_EQ(d.next(f), Status::kFrame);
  inspect::v1::Envelope e;
  EXPECT_TRUE(DelimitedDecoder::parse(f, e));
  EXPECT_EQ(e.body_case(), inspect::v1::Envelope::BODY_NOT_SET);
}

TEST(Delimited, LongStreamDoesNotGrowTheBuffer) {
  std::string one;
  appendDelimited(telemetry(1), one);
  DelimitedDecoder d;
  for (int i = 0; i < 10000; ++i) {
    d.append(one.data(), one.size());
    ASSERT_EQ(drain(d).size(), 1u);
  }
  EXPECT_EQ(d.buffered(), 0u);
}
