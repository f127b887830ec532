// Inputs the user names are checked before they are read (model/common/input_file.hpp, issue 41): a device
// such as /dev/zero or a folder is refused at once, naming it; a file over the cap from its size; a pipe is
// read up to the cap and no further.
#include <sys/stat.h>

#include <unistd.h>

#include <csignal>
#include <cstdio>

#include <string>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/common/input_file.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

TEST(InputFiles, ACampaignFromADeviceIsRefusedBeforeAByteIsRead) {
  // --campaign /dev/zero took 4.2 GB before it was refused.
  try {
    readCampaignFile("/dev/zero");
    ADD_FAILURE() << "/dev/zero was read as a campaign";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), HasSubstr("/dev/zero is a device, not a file (the measurement file)"));
  }
  try {
    readCampaignFile("/tmp");
    ADD_FAILURE() << "a folder was read as a campaign";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), HasSubstr("/tmp is a folder, not a file"));
  }
}

TEST(InputFiles, APipeIsReadUpToTheCapAndNoFurther) {
  char pattern[] = "/tmp/jointcomp-input-XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const std::string fifo = std::string(pattern) + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::signal(SIGPIPE, SIG_IGN);  // the writer sees EPIPE when the reader gives up, not a signal
  // A writer that sends more than the cap, then ends (it is cut off by EPIPE once the reader gives up).
  std::thread writer([&] {
    FILE* out = std::fopen(fifo.c_str(), "w");
    if (!out) return;
    const std::string block(4096, 'x');
    for (int i = 0; i < 64 && std::fwrite(block.data(), 1, block.size(), out) == block.size(); ++i) {}
    std::fclose(out);
  });
  try {
    readInputFile(fifo, "test input", 10000);
    ADD_FAILURE() << "a pipe was read past the cap";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("the test input is larger than 10000 bytes"));
  }
  writer.join();
  ::unlink(fifo.c_str());
  ::rmdir(pattern);
}

}  // namespace
}  // namespace jointcomp
