// Fio v3 hardware wiring for pb::Particle: servo, photocells, XBee, EEPROM and the watchdog.
// All behaviour lives in firmware/lib; this file only moves bits between pins and the logic.

// clang-format off
// The logic comes first: Arduino.h defines function-like macros (round, min, max, abs) that
// would rewrite the logic's member functions of the same names.
#include "particle.h"

#include <Arduino.h>
#include <avr/eeprom.h>
#include <avr/wdt.h>
#include <util/atomic.h>

#include <new>

#include "usb_upload_port.h"
// clang-format on

// ---- reset cause ----------------------------------------------------------------------------

// Filled before the C runtime clears .bss, so it must live in .noinit.
uint8_t g_reset_flags __attribute__((section(".noinit")));

// Runs from .init3, before .data/.bss are set up and long before setup(): a watchdog reset
// leaves the watchdog running at its shortest period (16 ms), which would bite again while the
// C runtime and the Arduino core start. WDRF forces WDE on, so MCUSR must be cleared first.
// (Behind the Caterina USB bootloader MCUSR arrives already cleared: the bootloader reads and
// clears it itself, so a particle flashed over USB reports cause 0.)
extern "C" void capture_reset_flags() __attribute__((naked, used, section(".init3")));
extern "C" void capture_reset_flags() {
  g_reset_flags = MCUSR;
  MCUSR = 0;
  wdt_disable();
}

namespace {

// ---- servo on D9 (PB5): Timer1 in CTC mode, 1 tick = 1 us -------------------------------------

const uint16_t kServoFrameUs = 20000;  // 50 Hz frames
const uint16_t kServoFrameMs = 20;
const uint16_t kServoMinUs = 500;
const uint16_t kServoMaxUs = 2500;
static_assert(kServoFrameMs == pb::kStepMs, "one servo step per frame");

// Compare value for the falling edge; the loop writes it, TIMER1_COMPA_vect reads it at the start
// of each frame, so a pulse never changes width half-way.
volatile uint16_t g_servo_fall_tick = 1500 - 1;
// Start of the current frame in ms since servo_begin(), advanced by TIMER1_COMPA_vect.
volatile uint32_t g_frame_start_ms = 0;

void servo_set(uint16_t pulse_us) {
  if (pulse_us < kServoMinUs) pulse_us = kServoMinUs;
  if (pulse_us > kServoMaxUs) pulse_us = kServoMaxUs;
  // The pin rises as TCNT1 wraps to 0 and falls as it leaves the compare value, so the pulse is
  // one tick longer than the value.
  const uint16_t fall = pulse_us - 1;
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    g_servo_fall_tick = fall;
  }
}

void servo_begin(uint16_t pulse_us) {
  servo_set(pulse_us);
  PORTB &= ~_BV(PORTB5);
  DDRB |= _BV(DDB5);
  // The Arduino core left Timer1 in 8-bit PWM for analogWrite(); take it over completely.
  TCCR1B = 0;
  TCCR1A = 0;
  TCCR1C = 0;
  TCNT1 = 0;
  OCR1A = kServoFrameUs - 1;  // TOP: the counter wraps every 20 000 ticks
  OCR1B = g_servo_fall_tick;
  TIFR1 = _BV(OCF1A) | _BV(OCF1B);
  TIMSK1 = _BV(OCIE1A) | _BV(OCIE1B);
  TCCR1B = _BV(WGM12) | _BV(CS11);  // CTC with TOP = OCR1A, clk/8 = 1 MHz at 8 MHz
}

// ---- clock: the servo frames ----------------------------------------------------------------

// The logic runs on Timer1 rather than millis(): the frames and the counter within one give the
// time to the millisecond (millis() moves in 2-3 ms jumps at 8 MHz), and, above all, the servo
// steps can be worked out for the frame that will show them. Time 0 is servo_begin().
struct Clock {
  uint32_t frame_ms;  // start of the current frame
  uint16_t us;        // into it

  uint32_t ms() const { return frame_ms + us / 1000u; }
  // Start of the next frame: the pulse set now is the one it carries.
  uint32_t next_frame_ms() const { return frame_ms + kServoFrameMs; }
};

Clock clock_now() {
  Clock c;
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    c.frame_ms = g_frame_start_ms;
    c.us = TCNT1;
    // The counter has wrapped but the interrupt that counts the new frame has not run yet. (The
    // flag rises while TCNT1 still reads TOP, hence the comparison, not just the flag.)
    if ((TIFR1 & _BV(OCF1A)) && c.us < kServoFrameUs / 2) c.frame_ms += kServoFrameMs;
  }
  return c;
}

// ---- ADC: one conversion in flight, collected on a later loop pass ---------------------------

const uint8_t kNoSensor = 0xFF;
// Channels are the MUX5:0 codes of ADCSRB/ADMUX. D4/A6 (ADC8) is not connected on the particle:
// its floating input is a noise source, and so is the temperature sensor's lowest bit.
const uint8_t kFloatingChannel = 0x20;
const uint8_t kTemperatureChannel = 0x27;
const uint8_t kRefAvcc = _BV(REFS0);                   // 3.3 V: the photocells' supply
const uint8_t kRefInternal = _BV(REFS1) | _BV(REFS0);  // 2.56 V: what the sensor needs

uint8_t g_adc_sensor = kNoSensor;  // sensor whose conversion is running

// A0..A5 are wired to ADC7, ADC6, ADC5, ADC4, ADC1, ADC0.
uint8_t sensor_channel(uint8_t sensor) {
  return sensor < 4 ? 7 - sensor : 5 - sensor;
}

void adc_start(uint8_t channel, uint8_t reference = kRefAvcc) {
  ADMUX = reference | (channel & 0x1F);  // right-adjusted result
  if (channel & 0x20) {
    ADCSRB |= _BV(MUX5);
  } else {
    ADCSRB &= ~_BV(MUX5);
  }
  ADCSRA |= _BV(ADSC);  // main() enabled the ADC at clk/64 = 125 kHz
}

bool adc_busy() {
  return (ADCSRA & _BV(ADSC)) != 0;
}

// Runs once, before the Particle exists (it needs the seed to be built), so this short wait
// (40 conversions, about 4.5 ms) is the only place that waits on the ADC. Photocells A0..A3 come
// last, between the floating pin's conversions, so that the reference has settled back to AVcc
// when the sampling proper begins. (Stepping through four of them rather than six spares a
// division: 46 B of flash.)
uint32_t seed_from_noise() {
  uint32_t seed = 2166136261u;  // FNV-1a over the raw readings
  for (uint8_t i = 0; i < 40; ++i) {
    if (i < 8) {
      adc_start(kTemperatureChannel, kRefInternal);
    } else {
      adc_start(i & 1 ? kFloatingChannel : sensor_channel((i >> 1) & 3));
    }
    while (adc_busy()) {
    }
    const uint16_t raw = ADC;
    seed = (seed ^ (raw & 0xFF)) * 16777619u;
    seed = (seed ^ (raw >> 8)) * 16777619u;
  }
  return seed;
}

// ---- watchdog -------------------------------------------------------------------------------

static_assert(kParticleWatchdogPeriod < 8, "the period's bits are WDP2..0 (WDP3 unused)");

// Resets the watchdog's count, unless the USB port asked for the bootloader: a host that opened
// the port at 1200 baud and closes it makes usb_upload_port.cpp store the bootloader's key and
// set the watchdog to 120 ms, expecting it to bite. Fed on, it never would and the upload would
// wait for the reset button. The period bits tell: only that code changes them.
void feed_watchdog() {
#ifndef PARTICLE_NO_USB
  const uint8_t period_bits = _BV(WDP3) | _BV(WDP2) | _BV(WDP1) | _BV(WDP0);
  if ((WDTCSR & period_bits) != kParticleWatchdogPeriod) return;
#endif
  wdt_reset();
}

// ---- EEPROM -------------------------------------------------------------------------------

class EepromStorage : public pb::Storage {
 public:
  uint8_t read(uint16_t address) const override {
    if (address > E2END) return 0xFF;
    return eeprom_read_byte(reinterpret_cast<const uint8_t *>(address));
  }
  void write(uint16_t address, uint8_t value) override {
    if (address > E2END) return;
    // Each changed byte costs ~3.4 ms: a long rewrite must not starve the watchdog.
    feed_watchdog();
    eeprom_update_byte(reinterpret_cast<uint8_t *>(address), value);
  }
};

EepromStorage g_storage;

// Built in setup(), once the reset cause and the seed are known; static storage so that avr-size
// counts it against the RAM budget.
alignas(pb::Particle) uint8_t g_particle_memory[sizeof(pb::Particle)];
pb::Particle *g_particle = nullptr;

// ---- Serial1 (XBee): USART1 at 9600 8N1, our own driver ------------------------------------
// The Arduino core's HardwareSerial (its virtual Print/Stream interface, two 64-byte rings,
// flush and peek) cost about 880 B of flash that the USB stack needs. This driver does what the
// particle uses: a receive ring filled by an interrupt, and one frame at a time sent from a
// linear buffer by the data-register-empty interrupt.

// 8 MHz / (16 * (51 + 1)) = 9615 baud, 0.2 % fast: inside the XBee's tolerance. Normal speed
// (no U2X) samples each bit 16 times, which tolerates more clock error than double speed.
const uint8_t kUbrr9600 = 51;

// Two-thirds of a 100-byte RF packet: enough for every burst the loop can fall behind on.
const uint8_t kRxRingSize = 64;  // a power of two
static_assert((kRxRingSize & (kRxRingSize - 1)) == 0, "ring index wraps with a mask");
volatile uint8_t g_rx_ring[kRxRingSize];
volatile uint8_t g_rx_head = 0;  // written by USART1_RX_vect
uint8_t g_rx_tail = 0;           // written by the loop; a full ring drops new bytes

// The frame being sent; the particle's own queue holds the ones after it.
uint8_t g_tx_frame[pb::kMaxPayload + pb::kFrameOverhead];
volatile uint8_t g_tx_next = 0;  // advanced by USART1_UDRE_vect
uint8_t g_tx_length = 0;

void serial_begin() {
  UBRR1 = kUbrr9600;
  UCSR1A = 0;
  UCSR1C = _BV(UCSZ11) | _BV(UCSZ10);  // 8 data bits, no parity, 1 stop bit
  UCSR1B = _BV(RXEN1) | _BV(TXEN1) | _BV(RXCIE1);
}

void serial_receive(uint32_t now_ms) {
  while (g_rx_tail != g_rx_head) {
    const uint8_t byte = g_rx_ring[g_rx_tail];
    g_rx_tail = static_cast<uint8_t>((g_rx_tail + 1) & (kRxRingSize - 1));
    g_particle->on_rx_byte(byte, now_ms);
  }
}

// Each frame goes out as an RF packet of its own: handed to the USART whole, then the line stays
// silent for Particle::kInterFrameGapMs (longer than the XBee's packetisation timeout).
enum TxPhase : uint8_t { kTxReady, kTxDraining, kTxGap };
TxPhase g_tx_phase = kTxReady;
uint32_t g_tx_gap_from_ms = 0;

// The interrupt has handed every byte to the USART (it then turns itself off) and the last stop
// bit has left the pin (TXC1, cleared when the frame started).
bool serial_drained() {
  return !(UCSR1B & _BV(UDRIE1)) && (UCSR1A & _BV(TXC1));
}

void serial_transmit(uint32_t now_ms) {
  if (g_tx_phase == kTxDraining) {
    if (!serial_drained()) return;
    g_tx_gap_from_ms = now_ms;
    g_tx_phase = kTxGap;
  }
  if (g_tx_phase == kTxGap) {
    if (now_ms - g_tx_gap_from_ms < pb::Particle::kInterFrameGapMs) return;
    g_tx_phase = kTxReady;
  }
  // take_tx() stops at the end of the frame at the head of the queue, and a frame fits.
  const size_t length = g_particle->take_tx(g_tx_frame, sizeof g_tx_frame);
  if (length == 0) return;
  g_tx_length = static_cast<uint8_t>(length);
  g_tx_next = 0;
  UCSR1A = _BV(TXC1);  // writing one clears the flag
  UCSR1B |= _BV(UDRIE1);
  g_tx_phase = kTxDraining;
}

void adc_poll() {
  if (g_adc_sensor != kNoSensor) {
    if (adc_busy()) return;
    g_particle->on_adc_sample(g_adc_sensor, ADC);
  }
  g_adc_sensor = g_particle->next_sensor();
  if (g_adc_sensor > 5) {
    g_adc_sensor = kNoSensor;
    return;
  }
  adc_start(sensor_channel(g_adc_sensor));
}

#ifdef PARTICLE_FAULT_INJECTION
// Test builds only: D2 (PD1) pulled up; an emulator test drives it low to hang the loop so the
// watchdog must reset the particle.
void fault_begin() {
  DDRD &= ~_BV(DDD1);
  PORTD |= _BV(PORTD1);
}

void fault_check() {
  if ((PIND & _BV(PIND1)) == 0) {
    for (;;) {
      __asm__ __volatile__("");  // a hang the compiler may not remove
    }
  }
}
#endif

}  // namespace

ISR(TIMER1_COMPA_vect) {
  PORTB |= _BV(PORTB5);
  OCR1B = g_servo_fall_tick;  // not double-buffered in CTC mode: set it while the pulse is high
  g_frame_start_ms = g_frame_start_ms + kServoFrameMs;
}

ISR(TIMER1_COMPB_vect) {
  PORTB &= ~_BV(PORTB5);
}

ISR(USART1_RX_vect) {
  const uint8_t byte = UDR1;  // read even when the ring is full, to clear the interrupt
  const uint8_t head = g_rx_head;
  const uint8_t next = static_cast<uint8_t>((head + 1) & (kRxRingSize - 1));
  if (next == g_rx_tail) return;  // full: the parser resynchronises on what follows
  g_rx_ring[head] = byte;
  g_rx_head = next;
}

ISR(USART1_UDRE_vect) {
  const uint8_t next = g_tx_next;
  UDR1 = g_tx_frame[next];
  g_tx_next = static_cast<uint8_t>(next + 1);
  if (next + 1 >= g_tx_length) UCSR1B &= ~_BV(UDRIE1);
}

void setup() {
  const uint8_t reset_flags = g_reset_flags;
#ifdef PARTICLE_FAULT_INJECTION
  fault_begin();
#endif
  const uint32_t seed = seed_from_noise();
  g_particle = new (g_particle_memory) pb::Particle(g_storage, reset_flags, seed);
  serial_begin();
  g_particle->begin(0);  // the clock starts with the servo's frames
  servo_begin(g_particle->servo_pulse_us());
  wdt_enable(kParticleWatchdogPeriod);
}

void loop() {
  feed_watchdog();
#ifdef PARTICLE_FAULT_INJECTION
  fault_check();
#endif
  const Clock clock = clock_now();
  const uint32_t now_ms = clock.ms();
  serial_receive(now_ms);
  adc_poll();
  // The new step is worked out in the first pass of a frame, and set long before the next frame
  // latches it: every frame shows exactly one step, the one due when it begins.
  g_particle->tick(now_ms, clock.next_frame_ms());
  servo_set(g_particle->servo_pulse_us());
  serial_transmit(now_ms);
}

// Replaces the Arduino core's main() and its init(), which sets up four timers for analogWrite()
// and millis() that the particle does not use (Timer1 is the servo's and the clock's).
int main() {
#ifdef PARTICLE_NO_USB
  // Without the USB stack nothing needs Timer0: the clock is Timer1, so no millis() interrupt
  // delays a servo edge.
#else
  // The USB code waits with the core's delay(), which counts Timer0 overflows (clk/64, as the
  // core's init() sets it up).
  TCCR0A = _BV(WGM01) | _BV(WGM00);
  TCCR0B = _BV(CS01) | _BV(CS00);
  TIMSK0 = _BV(TOIE0);
#endif
  ADCSRA = _BV(ADEN) | _BV(ADPS2) | _BV(ADPS1);  // clk/64: 125 kHz at 8 MHz
  sei();
#ifndef PARTICLE_NO_USB
  // The USB CDC port: a host that opens it at 1200 baud and closes it resets the particle into
  // the Caterina bootloader, so uploads need no button (see bootloader_touch_pending()).
  USBDevice.attach();
#endif
  setup();
  for (;;) loop();
}
