// The one doctest main of the firmware-logic unit tests; every other test file only adds cases.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest.h>

int main(int argc, char **argv) {
  doctest::Context context;
#ifdef PIO_UNIT_TESTING
  // PlatformIO's test runner reads every case's result from the output and judges the run
  // itself, so it needs successes reported and the exit code left alone.
  context.setOption("success", true);
  context.setOption("no-exitcode", true);
#endif
  context.applyCommandLine(argc, argv);
  return context.run();
}
