// The one doctest main of the firmware-logic unit tests; every other test file only adds cases.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest.h>
