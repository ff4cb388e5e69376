// The particle's USB port, reduced to what uploads need: a CDC ACM serial port whose 1200-baud
// touch resets the Fio into its Caterina bootloader. No data ever flows over it.
//
// The Arduino core's USBCore drives the USB controller and asks two functions for the CDC
// function: CDC_GetInterface() for its descriptors and CDC_Setup() for its class requests. The
// core's own CDC.cpp also builds the Serial object (a Print/Stream with buffers and a vtable the
// particle never uses: about 1.1 KB of flash and 110 B of RAM); defining the two functions here
// keeps that file out of the link. The descriptors and requests are those of the USB CDC 1.2 and
// PSTN 1.2 specifications; the bootloader handshake is Caterina's (key below).
#ifndef PARTICLE_NO_USB

// clang-format off
#include <Arduino.h>
#include <avr/pgmspace.h>
#include <avr/wdt.h>
// clang-format on

#include "usb_upload_port.h"

namespace {

// Interface, endpoint and size numbers USBCore sets its endpoints up with (USBDesc.h).
static_assert(CDC_ACM_INTERFACE == 0 && CDC_DATA_INTERFACE == 1, "interface numbers");
static_assert(CDC_ENDPOINT_ACM == 1 && CDC_ENDPOINT_OUT == 2 && CDC_ENDPOINT_IN == 3,
              "endpoint numbers");
static_assert(USB_EP_SIZE == 64, "bulk endpoint size");

// The CDC function as the configuration descriptor carries it, 66 bytes, one descriptor a line.
// clang-format off
const uint8_t kCdcFunction[] PROGMEM = {
    // Interface association: interfaces 0 and 1 are one function, CDC, abstract control model.
    8, 0x0B, 0, 2, 0x02, 0x02, 0x00, 0,
    // Interface 0, communication class, ACM, one endpoint.
    9, 0x04, 0, 0, 1, 0x02, 0x02, 0x00, 0,
    // Class-specific: header (CDC 1.10), call management (data interface 1), ACM capabilities
    // (line coding, control line state, break), union (master 0, slave 1).
    5, 0x24, 0x00, 0x10, 0x01,
    5, 0x24, 0x01, 0x01, 1,
    4, 0x24, 0x02, 0x06,
    5, 0x24, 0x06, 0, 1,
    // Endpoint 1 IN, interrupt, 16 bytes, every 64 ms: notifications (never sent).
    7, 0x05, 0x81, 0x03, 16, 0, 64,
    // Interface 1, data class, two endpoints.
    9, 0x04, 1, 0, 2, 0x0A, 0x00, 0x00, 0,
    // Endpoint 2 OUT and endpoint 3 IN, bulk, 64 bytes.
    7, 0x05, 0x02, 0x02, 64, 0, 0,
    7, 0x05, 0x83, 0x02, 64, 0, 0,
};
// clang-format on
static_assert(sizeof kCdcFunction == 66,
              "IAD 8 + interfaces 2 x 9 + functional 19 + endpoints 3 x 7");

// Line coding as the host last set it: rate (little-endian), stop bits, parity, data bits. The
// host reads it back, so it is kept whole.
uint8_t g_line_coding[7] = {0x80, 0x25, 0, 0, 0, 0, 8};  // 9600 8N1 until told otherwise
const uint32_t kTouchBaud = 1200;

// Caterina stays in the bootloader after a watchdog reset when it finds this key in RAM: at
// RAMEND - 1 for a bootloader that says so at the end of flash, at 0x0800 for the older ones
// (the Fio v3's). Neither spot is in use by the firmware (static data ends below 0x0400 and the
// stack never comes down to 0x0800).
const uint16_t kBootKey = 0x7777;
const uint16_t kNewBootloaderSignature = 0xDCFB;

volatile uint16_t *boot_key_address() {
  const uint16_t address =
      pgm_read_word(FLASHEND - 1) == kNewBootloaderSignature ? RAMEND - 1 : 0x0800;
  return reinterpret_cast<volatile uint16_t *>(address);
}

// SET_CONTROL_LINE_STATE: a host closing the port it opened at 1200 baud drops DTR. The key goes
// into RAM and the watchdog gets 120 ms, which the loop then lets run out (feed_watchdog()). Some
// hosts toggle DTR while they set a port up, so DTR coming back before that cancels the reset.
void on_control_line_state(bool dtr) {
  uint32_t baud;
  memcpy(&baud, g_line_coding, sizeof baud);
  volatile uint16_t *key = boot_key_address();
  if (baud == kTouchBaud && !dtr) {
    *key = kBootKey;
    wdt_enable(WDTO_120MS);
  } else if (*key == kBootKey) {
    *key = 0;
    wdt_enable(kParticleWatchdogPeriod);
  }
}

}  // namespace

int CDC_GetInterface(uint8_t *interface_count) {
  *interface_count += 2;
  return USB_SendControl(TRANSFER_PGM, kCdcFunction, sizeof kCdcFunction);
}

bool CDC_Setup(USBSetup &setup) {
  if (setup.bmRequestType == REQUEST_DEVICETOHOST_CLASS_INTERFACE) {
    if (setup.bRequest != CDC_GET_LINE_CODING) return false;
    USB_SendControl(0, g_line_coding, sizeof g_line_coding);
    return true;
  }
  if (setup.bmRequestType != REQUEST_HOSTTODEVICE_CLASS_INTERFACE) return false;
  if (setup.bRequest == CDC_SET_LINE_CODING) {
    USB_RecvControl(g_line_coding, sizeof g_line_coding);
  } else if (setup.bRequest == CDC_SET_CONTROL_LINE_STATE) {
    on_control_line_state((setup.wValueL & 0x01) != 0);
  }
  return true;  // SEND_BREAK and the rest: accepted, nothing to do
}

#endif  // PARTICLE_NO_USB
