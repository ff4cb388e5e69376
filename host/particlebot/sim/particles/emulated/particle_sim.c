// Runs one particle's real firmware ELF in simavr, paced by simulated time, for a driver process.
//
// particle_sim [--eeprom-in FILE] [--eeprom-out FILE] [--baud N] ELF
//
// The driver writes commands to stdin, one per line, and reads events from stdout, one per line.
// Nothing runs between commands: simulated time advances only inside `run`/`for`, so a driver
// can hold any number of harnesses in lockstep by giving each the same `run C` and reading each
// up to its `at` line. All times are CPU cycles at 8 MHz (8 per microsecond) counted from power-on
// and never reset, not even when the AVR resets. Numbers are decimal, bytes are hex.
//
// Commands
//   run C          run until cycle C (no-op if C is not ahead); answered by `at C'`, C' >= C by
//                  at most one instruction
//   for US         run for US microseconds; answered by `at C'`
//   rx HEX         queue bytes for the UART1 receiver; they arrive back to back at the wire rate
//                  (10 bits per byte: 1041.67 us at 9600 baud) after anything already queued
//   light K MV     photocell K (0..5, pin A<K>) reads MV millivolts from now on (AVcc = 3300)
//   adc CH MV      ADC input CH (0..7) reads MV millivolts (photocells use 7 6 5 4 1 0)
//   temp MV        the temperature sensor reads MV millivolts; its noise (with the photocells')
//                  seeds the firmware's random numbers, so give each particle its own value
//   pin PB LEVEL   drive input pin PB (port letter and bit, e.g. D1 = D2, the fault pin of the
//                  fault-injection build) to LEVEL 0 or 1; kept across resets
//   eeprom         answered by `eeprom HEX` (the whole 1024 bytes)
//   usb-touch      what the core's USB code does on a 1200-baud touch: bootloader key at 0x0800,
//                  watchdog set to 120 ms (simavr has no USB)
//   quit           writes --eeprom-out if given, answers `bye C` and exits
// Events (in simulated-time order, before the `at` that ends the run they happened in)
//   hello particle_sim 1 F       once at start; F is the clock in Hz
//   tx C XX        the firmware finished writing byte XX to UART1 at cycle C
//   servo C L      pin D9 (PB5) went to level L at cycle C
//   reset C XX     the AVR reset at cycle C (watchdog, ...); XX is MCUSR as the firmware will
//                  find it (bit 3 = watchdog); a servo pulse in progress ends with the reset
//   crashed C      the core stopped (sleep with interrupts off, invalid opcode); runs do nothing
//   error TEXT     a malformed command; it was ignored
#define _GNU_SOURCE
#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "avr_adc.h"
#include "avr_eeprom.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "sim_avr.h"
#include "sim_elf.h"

#define MCU_NAME "atmega32u4"
#define CPU_HZ 8000000u
#define SUPPLY_MV 3300u
#define EEPROM_SIZE 1024u
#define MCUSR_DATA_ADDR 0x54u  // MCUSR: I/O 0x34 + 0x20
#define MCUSR_PORF 0x01u
#define WDTCSR_DATA_ADDR 0x60u
#define USB_BOOT_KEY_ADDR 0x0800u
#define RX_QUEUE_SIZE 4096u
#define SENSOR_COUNT 6
#define DRIVEN_PINS_MAX 8
// simavr 1.6 holds values for ADC0..7 only (ADC8..13 read garbage there).
#define ADC_INPUTS 8

// Photocell k sits on pin A<k>, wired to these ADC channels.
static const int kSensorChannel[SENSOR_COUNT] = {7, 6, 5, 4, 1, 0};

typedef struct {
  char port;
  int bit;
  int level;
} driven_pin_t;

static struct {
  avr_t *avr;
  FILE *out;               // the protocol stream; stdout itself is pointed at stderr
  avr_cycle_count_t base;  // cycles lost to resets that zeroed avr->cycle: time = base + cycle
  bool reset_seen;
  avr_cycle_count_t reset_at;
  avr_cycle_count_t reset_raw_cycle;
  bool crashed;
  int servo_level;
  void (*core_reset)(avr_t *);
  // UART1 receive queue: byte i starts on the wire at cycle rx_due[i] (absolute).
  uint8_t rx_byte[RX_QUEUE_SIZE];
  avr_cycle_count_t rx_due[RX_QUEUE_SIZE];
  unsigned rx_head, rx_count;
  uint64_t rx_line_free_scaled;  // when the wire is free again, in cycles * baud
  uint32_t baud;
  avr_irq_t *uart_in;
  avr_uart_t *uart;  // UART1, whose byte timing fix_uart_timing() corrects
  avr_cycle_count_t uart_byte_cycles;
  uint32_t adc_mv[ADC_INPUTS];
  uint32_t temperature_mv;
  driven_pin_t pins[DRIVEN_PINS_MAX];
  int pin_count;
} sim;

// While a reset is being handled the clock reads the instant of the reset.
static avr_cycle_count_t now(void) {
  return sim.reset_seen ? sim.reset_at : sim.base + sim.avr->cycle;
}

static void emit(const char *format, ...) __attribute__((format(printf, 1, 2)));
static void emit(const char *format, ...) {
  va_list args;
  va_start(args, format);
  vfprintf(sim.out, format, args);
  va_end(args);
  fputc('\n', sim.out);
}

static void logger(avr_t *avr, const int level, const char *format, va_list args) {
  (void)avr;
  if (level <= LOG_WARNING) vfprintf(stderr, format, args);
}

// The default sleep waits on the wall clock; simulated time must not.
static void sleep_without_waiting(avr_t *avr, avr_cycle_count_t how_long) {
  (void)avr;
  (void)how_long;
}

static void on_uart_tx(avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq;
  (void)param;
  emit("tx %" PRIu64 " %02x", (uint64_t)now(), value & 0xFF);
}

static void on_servo_pin(avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq;
  (void)param;
  const int level = value ? 1 : 0;
  if (level == sim.servo_level) return;
  sim.servo_level = level;
  emit("servo %" PRIu64 " %d", (uint64_t)now(), level);
}

// Called from avr_reset(). Some simavr versions then zero avr->cycle, others do not: after_reset()
// looks which happened.
static void on_reset(avr_t *avr) {
  sim.reset_at = now();
  sim.reset_raw_cycle = avr->cycle;
  sim.reset_seen = true;
  if (sim.core_reset) sim.core_reset(avr);
}

static void apply_adc(int channel) {
  avr_raise_irq(avr_io_getirq(sim.avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + channel),
                sim.adc_mv[channel]);
}

static void apply_temperature(void) {
  avr_raise_irq(avr_io_getirq(sim.avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_TEMP), sim.temperature_mv);
}

static void apply_pin(const driven_pin_t *pin) {
  // An external drive beats the internal pull-up: simavr resolves it on every PORT write, where
  // a bare IRQ would be overwritten as soon as the firmware enables the pull-up.
  avr_ioport_external_t external = {.name = (unsigned long)pin->port, .mask = 0, .value = 0};
  for (int i = 0; i < sim.pin_count; ++i) {
    if (sim.pins[i].port != pin->port) continue;
    external.mask |= 1u << sim.pins[i].bit;
    if (sim.pins[i].level) external.value |= 1u << sim.pins[i].bit;
  }
  avr_ioctl(sim.avr, AVR_IOCTL_IOPORT_SET_EXTERNAL(pin->port), &external);
  avr_irq_t *irq = avr_io_getirq(sim.avr, AVR_IOCTL_IOPORT_GETIRQ(pin->port), pin->bit);
  // Raise the opposite level first: an IRQ that already holds the value does not propagate.
  avr_raise_irq(irq, !pin->level);
  avr_raise_irq(irq, pin->level);
}

// After a reset the I/O registers are zero again; the outside world is not.
static void after_reset(void) {
  if (sim.avr->cycle < sim.reset_raw_cycle) sim.base += sim.reset_raw_cycle;
  sim.reset_seen = false;
  if (sim.servo_level) {
    sim.servo_level = 0;
    emit("servo %" PRIu64 " 0", (uint64_t)sim.reset_at);
  }
  emit("reset %" PRIu64 " %02x", (uint64_t)sim.reset_at, sim.avr->data[MCUSR_DATA_ADDR]);
  for (int ch = 0; ch < ADC_INPUTS; ++ch) apply_adc(ch);
  apply_temperature();
  for (int i = 0; i < sim.pin_count; ++i) apply_pin(&sim.pins[i]);
}

// simavr 1.6 times every UART byte as 11 bits (it counts a parity bit even when there is none),
// so the firmware would send and take bytes 10 % slower than the 8N1 wire, and a receiver fed at
// the wire rate would overflow simavr's 64-byte input FIFO after ~640 bytes. Its byte time is
// recomputed from UBRR1 and U2X1 whenever the firmware sets the baud rate; put 10 bits back.
// Runs after every instruction, so it only compares until simavr has changed the value.
static void fix_uart_timing(void) {
  avr_uart_t *u = sim.uart;
  if (u->cycles_per_byte == sim.uart_byte_cycles) return;
  const uint32_t ubrr =
      avr_regbit_get(sim.avr, u->ubrrl) | (avr_regbit_get(sim.avr, u->ubrrh) << 8);
  sim.uart_byte_cycles = 10u * (ubrr + 1) * (avr_regbit_get(sim.avr, u->u2x) ? 8u : 16u);
  u->cycles_per_byte = sim.uart_byte_cycles;
}

static avr_uart_t *find_uart(char name) {
  for (avr_io_t *io = sim.avr->io_port; io; io = io->next) {
    if (strcmp(io->kind, "uart") == 0 && ((avr_uart_t *)io)->name == name) return (avr_uart_t *)io;
  }
  return NULL;
}

static avr_cycle_count_t wake(avr_t *avr, avr_cycle_count_t when, void *param) {
  (void)avr;
  (void)when;
  (void)param;
  return 0;
}

// Runs the core until absolute cycle `target`, delivering queued UART bytes on time.
static void run_until(avr_cycle_count_t target) {
  while (!sim.crashed && now() < target) {
    avr_cycle_count_t next = target;
    if (sim.rx_count > 0 && sim.rx_due[sim.rx_head] < next) next = sim.rx_due[sim.rx_head];
    // A cycle timer at the next due time keeps a sleeping core from jumping past it.
    avr_cycle_timer_cancel(sim.avr, wake, NULL);
    avr_cycle_timer_register(sim.avr, next - now(), wake, NULL);
    while (now() < next && !sim.reset_seen) {
      const int state = avr_run(sim.avr);
      fix_uart_timing();
      if (state == cpu_Done || state == cpu_Crashed) {
        sim.crashed = true;
        emit("crashed %" PRIu64, (uint64_t)now());
        break;
      }
    }
    if (sim.reset_seen) after_reset();
    while (sim.rx_count > 0 && sim.rx_due[sim.rx_head] <= now()) {
      avr_raise_irq(sim.uart_in, sim.rx_byte[sim.rx_head]);
      sim.rx_head = (sim.rx_head + 1) % RX_QUEUE_SIZE;
      --sim.rx_count;
    }
  }
  avr_cycle_timer_cancel(sim.avr, wake, NULL);
}

static void queue_rx(const char *hex) {
  const size_t len = strlen(hex);
  if (len % 2 != 0) {
    emit("error rx needs an even number of hex digits");
    return;
  }
  const uint64_t byte_scaled = 10ull * CPU_HZ;  // start + 8 data + stop bits, in cycles * baud
  const uint64_t now_scaled = (uint64_t)now() * sim.baud;
  if (sim.rx_line_free_scaled < now_scaled) sim.rx_line_free_scaled = now_scaled;
  for (size_t i = 0; i < len; i += 2) {
    unsigned value;
    if (sscanf(hex + i, "%2x", &value) != 1) {
      emit("error bad hex in rx");
      return;
    }
    if (sim.rx_count == RX_QUEUE_SIZE) {
      emit("error rx queue full");
      return;
    }
    const unsigned slot = (sim.rx_head + sim.rx_count) % RX_QUEUE_SIZE;
    sim.rx_byte[slot] = (uint8_t)value;
    // Handed to simavr as its start bit begins: simavr's receiver then takes one byte time
    // before it raises RXC, so the firmware gets the byte as its stop bit ends, as on the chip.
    sim.rx_due[slot] = (sim.rx_line_free_scaled + sim.baud - 1) / sim.baud;
    sim.rx_line_free_scaled += byte_scaled;
    ++sim.rx_count;
  }
}

static void set_pin(char port, int bit, int level) {
  for (int i = 0; i < sim.pin_count; ++i) {
    if (sim.pins[i].port == port && sim.pins[i].bit == bit) {
      sim.pins[i].level = level;
      apply_pin(&sim.pins[i]);
      return;
    }
  }
  if (sim.pin_count == DRIVEN_PINS_MAX) {
    emit("error too many driven pins");
    return;
  }
  sim.pins[sim.pin_count] = (driven_pin_t){port, bit, level};
  apply_pin(&sim.pins[sim.pin_count++]);
}

static void eeprom_access(uint8_t *bytes, bool write) {
  avr_eeprom_desc_t desc = {.ee = bytes, .offset = 0, .size = EEPROM_SIZE};
  avr_ioctl(sim.avr, write ? AVR_IOCTL_EEPROM_SET : AVR_IOCTL_EEPROM_GET, &desc);
  // GET points desc.ee at the simulator's own copy instead of filling ours.
  if (!write && desc.ee != bytes) memcpy(bytes, desc.ee, EEPROM_SIZE);
}

static bool load_eeprom_file(const char *path) {
  uint8_t bytes[EEPROM_SIZE];
  memset(bytes, 0xFF, sizeof bytes);  // a short file leaves the rest erased
  FILE *file = fopen(path, "rb");
  if (!file) {
    fprintf(stderr, "particle_sim: %s: %s\n", path, strerror(errno));
    return false;
  }
  const size_t got = fread(bytes, 1, sizeof bytes, file);
  (void)got;
  fclose(file);
  eeprom_access(bytes, true);
  return true;
}

static bool save_eeprom_file(const char *path) {
  uint8_t bytes[EEPROM_SIZE];
  eeprom_access(bytes, false);
  FILE *file = fopen(path, "wb");
  if (!file || fwrite(bytes, 1, sizeof bytes, file) != sizeof bytes) {
    fprintf(stderr, "particle_sim: %s: %s\n", path, strerror(errno));
    if (file) fclose(file);
    return false;
  }
  return fclose(file) == 0;
}

// Writes an I/O register as an instruction would, through the module that owns it.
static void io_write(uint16_t address, uint8_t value) {
  avr_t *avr = sim.avr;
  const int io = AVR_DATA_TO_IO(address);
  if (avr->io[io].w.c) {
    avr->io[io].w.c(avr, address, value, avr->io[io].w.param);
  } else {
    avr->data[address] = value;
  }
}

// What the Arduino core's USB CDC code does when a host that opened the port at 1200 baud drops
// DTR (the "1200-baud touch" before an upload): it stores the Caterina bootloader's key 0x7777 at
// 0x0800 and sets the watchdog to 120 ms (WDCE|WDE, then WDE|WDP1|WDP0 within four cycles),
// expecting it to reset the chip into the bootloader. simavr has no USB, so this stands in for it.
static void usb_touch(void) {
  sim.avr->data[USB_BOOT_KEY_ADDR] = 0x77;
  sim.avr->data[USB_BOOT_KEY_ADDR + 1] = 0x77;
  io_write(WDTCSR_DATA_ADDR, 0x18);
  io_write(WDTCSR_DATA_ADDR, 0x0B);
}

static void dump_eeprom(void) {
  uint8_t bytes[EEPROM_SIZE];
  char hex[2 * EEPROM_SIZE + 1];
  eeprom_access(bytes, false);
  for (unsigned i = 0; i < EEPROM_SIZE; ++i) snprintf(hex + 2 * i, 3, "%02x", bytes[i]);
  emit("eeprom %s", hex);
}

// Handles one command line; returns false on quit.
static bool command(char *line, const char *eeprom_out) {
  char verb[16] = "";
  char arg[16] = "";
  uint64_t a = 0;
  uint64_t b = 0;
  int consumed = 0;
  if (sscanf(line, "%15s%n", verb, &consumed) != 1) return true;  // blank line
  const char *rest = line + consumed;
  if (strcmp(verb, "run") == 0 && sscanf(rest, "%" SCNu64, &a) == 1) {
    run_until(a);
    emit("at %" PRIu64, (uint64_t)now());
  } else if (strcmp(verb, "for") == 0 && sscanf(rest, "%" SCNu64, &a) == 1) {
    run_until(now() + a * (CPU_HZ / 1000000u));
    emit("at %" PRIu64, (uint64_t)now());
  } else if (strcmp(verb, "rx") == 0) {
    char *hex = strtok((char *)rest, " \t\r\n");
    if (hex) queue_rx(hex);
  } else if (strcmp(verb, "light") == 0 && sscanf(rest, "%" SCNu64 " %" SCNu64, &a, &b) == 2 &&
             a < SENSOR_COUNT) {
    sim.adc_mv[kSensorChannel[a]] = (uint32_t)b;
    apply_adc(kSensorChannel[a]);
  } else if (strcmp(verb, "adc") == 0 && sscanf(rest, "%" SCNu64 " %" SCNu64, &a, &b) == 2 &&
             a < ADC_INPUTS) {
    sim.adc_mv[a] = (uint32_t)b;
    apply_adc((int)a);
  } else if (strcmp(verb, "temp") == 0 && sscanf(rest, "%" SCNu64, &a) == 1) {
    sim.temperature_mv = (uint32_t)a;
    apply_temperature();
  } else if (strcmp(verb, "pin") == 0 && sscanf(rest, "%15s %" SCNu64, arg, &a) == 2 &&
             arg[0] >= 'B' && arg[0] <= 'F' && arg[1] >= '0' && arg[1] <= '7' && arg[2] == 0 &&
             a <= 1) {
    set_pin(arg[0], arg[1] - '0', (int)a);
  } else if (strcmp(verb, "eeprom") == 0) {
    dump_eeprom();
  } else if (strcmp(verb, "usb-touch") == 0) {
    usb_touch();
  } else if (strcmp(verb, "quit") == 0) {
    if (eeprom_out) save_eeprom_file(eeprom_out);
    emit("bye %" PRIu64, (uint64_t)now());
    return false;
  } else {
    line[strcspn(line, "\r\n")] = 0;
    emit("error unknown or malformed command: %s", line);
  }
  return true;
}

int main(int argc, char **argv) {
  const char *eeprom_in = NULL;
  const char *eeprom_out = NULL;
  const char *elf = NULL;
  sim.baud = 9600;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--eeprom-in") == 0 && i + 1 < argc) {
      eeprom_in = argv[++i];
    } else if (strcmp(argv[i], "--eeprom-out") == 0 && i + 1 < argc) {
      eeprom_out = argv[++i];
    } else if (strcmp(argv[i], "--baud") == 0 && i + 1 < argc) {
      sim.baud = (uint32_t)strtoul(argv[++i], NULL, 10);
    } else if (argv[i][0] != '-' && !elf) {
      elf = argv[i];
    } else {
      elf = NULL;
      break;
    }
  }
  if (!elf || sim.baud == 0) {
    fprintf(stderr, "usage: %s [--eeprom-in FILE] [--eeprom-out FILE] [--baud N] ELF\n", argv[0]);
    return 2;
  }

  // libsimavr prints to stdout in places; keep the protocol stream to ourselves.
  const int protocol_fd = dup(STDOUT_FILENO);
  if (protocol_fd < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) return 1;
  sim.out = fdopen(protocol_fd, "w");
  if (!sim.out) return 1;
  avr_global_logger_set(logger);

  elf_firmware_t firmware;
  memset(&firmware, 0, sizeof firmware);
  if (elf_read_firmware(elf, &firmware) != 0) {
    fprintf(stderr, "particle_sim: cannot read %s\n", elf);
    return 1;
  }
  sim.avr = avr_make_mcu_by_name(MCU_NAME);
  if (!sim.avr) return 1;
  avr_init(sim.avr);
  avr_load_firmware(sim.avr, &firmware);
  sim.avr->frequency = CPU_HZ;
  sim.avr->vcc = sim.avr->avcc = sim.avr->aref = SUPPLY_MV;
  sim.avr->sleep = sleep_without_waiting;
  sim.core_reset = sim.avr->reset;
  sim.avr->reset = on_reset;
  if (eeprom_in && !load_eeprom_file(eeprom_in)) return 1;

  uint32_t flags = 0;
  avr_ioctl(sim.avr, AVR_IOCTL_UART_GET_FLAGS('1'), &flags);
  flags &= ~(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
  avr_ioctl(sim.avr, AVR_IOCTL_UART_SET_FLAGS('1'), &flags);
  sim.uart_in = avr_io_getirq(sim.avr, AVR_IOCTL_UART_GETIRQ('1'), UART_IRQ_INPUT);
  sim.uart = find_uart('1');
  if (!sim.uart) {
    fprintf(stderr, "particle_sim: no UART1 in this simavr\n");
    return 1;
  }
  avr_irq_register_notify(avr_io_getirq(sim.avr, AVR_IOCTL_UART_GETIRQ('1'), UART_IRQ_OUTPUT),
                          on_uart_tx, NULL);
  avr_irq_register_notify(avr_io_getirq(sim.avr, AVR_IOCTL_IOPORT_GETIRQ('B'), IOPORT_IRQ_PIN5),
                          on_servo_pin, NULL);

  // Photocells start at mid-scale so that none looks stuck before the driver sets the light.
  for (int k = 0; k < SENSOR_COUNT; ++k) sim.adc_mv[kSensorChannel[k]] = SUPPLY_MV / 2;
  // About what the sensor gives at room temperature (datasheet: 1 mV per kelvin, ~300 mV at 25 C).
  sim.temperature_mv = 300;
  for (int ch = 0; ch < ADC_INPUTS; ++ch) apply_adc(ch);
  apply_temperature();
  // A real chip starts with the power-on flag set.
  sim.avr->data[MCUSR_DATA_ADDR] |= MCUSR_PORF;

  emit("hello particle_sim 1 %u", CPU_HZ);
  fflush(sim.out);
  char line[8192];
  bool more = true;
  while (more && fgets(line, sizeof line, stdin)) {
    more = command(line, eeprom_out);
    fflush(sim.out);
  }
  if (more && eeprom_out) save_eeprom_file(eeprom_out);  // stdin closed without quit
  avr_terminate(sim.avr);
  return 0;
}
