// What main.cpp and the USB upload port share: the watchdog period the particle runs with.
#ifndef PARTICLEBOT_USB_UPLOAD_PORT_H
#define PARTICLEBOT_USB_UPLOAD_PORT_H

#include <avr/wdt.h>

// A stuck loop resets the particle after this long. A 1200-baud touch on the USB port sets a
// shorter period (WDTO_120MS) for the bootloader; feed_watchdog() in main.cpp tells the two
// apart, and the port restores this one when the host cancels the touch.
const uint8_t kParticleWatchdogPeriod = WDTO_250MS;

#endif  // PARTICLEBOT_USB_UPLOAD_PORT_H
