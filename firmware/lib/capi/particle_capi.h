// C interface to the firmware logic for PC builds: the host's virtual particles and the pytest
// suite load build/native/libparticle.so through ctypes and drive the very code that is flashed.
// This file is the contract between firmware/lib and host/particlebot/firmware/native.py:
// change both together. Nothing here is compiled for the AVR.
#ifndef PARTICLEBOT_PARTICLE_CAPI_H
#define PARTICLEBOT_PARTICLE_CAPI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PB_SENSOR_COUNT 6
#define PB_EEPROM_SIZE 1024
// The longest frame: max_payload + 8 bytes of sync, header and CRC.
#define PB_MAX_FRAME 56

typedef struct pb_particle pb_particle;

// ---- one whole particle: the same Particle controller main.cpp runs --------------------------

// Creates a particle from an EEPROM image (NULL or shorter than PB_EEPROM_SIZE: the rest reads as
// erased 0xFF, as on a new chip). reset_cause is the MCUSR value the particle reports.
// rng_seed stands in for the ADC noise the real particle seeds its jitter from.
pb_particle *pb_particle_new(const uint8_t *eeprom, size_t eeprom_len, uint8_t reset_cause,
                             uint32_t rng_seed);
void pb_particle_free(pb_particle *particle);

// Raw ADC values (0..1023) each photocell reads from now on, until changed. Every tick the
// particle draws as many samples as the real main loop would in the elapsed time (one ADC
// conversion per ~125 us), 50 per sensor per reading.
void pb_particle_set_adc(pb_particle *particle, const uint16_t adc[PB_SENSOR_COUNT]);

// Bytes that arrived on Serial1.
void pb_particle_receive(pb_particle *particle, const uint8_t *bytes, size_t count);

// Advances the logic to now_ms (monotonic, may wrap at 2^32). Call at least every 5 ms of
// simulated time for servo steps to fall on their 20 ms boundaries.
void pb_particle_tick(pb_particle *particle, uint32_t now_ms);

// Many particles at once, for swarms (one call instead of three per particle and tick): each of
// particles[0..count) is ticked to now_ms as pb_particle_tick does, then radius_um[i] receives its
// radius and tx_waiting[i] whether a frame waits in its Serial1 queue (1) or not (0).
void pb_particles_tick(pb_particle *const *particles, size_t count, uint32_t now_ms,
                       uint32_t *radius_um, uint8_t *tx_waiting);

// Moves up to capacity bytes of the frame at the head of the Serial1 queue into out and returns
// how many; it never goes past that frame's end, so a call with room for a whole frame
// (PB_MAX_FRAME) takes exactly one frame, as main.cpp hands one frame at a time to Serial1.
// Call again for the next frame; 0 when the queue is empty.
size_t pb_particle_transmit(pb_particle *particle, uint8_t *out, size_t capacity);

// The silence main.cpp keeps on Serial1 after a frame's last byte before it hands over the next
// (Particle::kInterFrameGapMs): a simulation of the serial link must keep it too, or the XBee
// would put two frames into one RF packet and cut a pair over 100 bytes apart.
uint8_t pb_inter_frame_gap_ms(void);

uint8_t pb_particle_id(const pb_particle *particle);
uint16_t pb_particle_servo_pulse_us(const pb_particle *particle);
uint32_t pb_particle_radius_um(const pb_particle *particle);

// Writes the payload of the STATUS frame the particle would send now; returns its length.
size_t pb_particle_status_payload(const pb_particle *particle, uint8_t *out, size_t capacity);

// Copies the particle's EEPROM image (PB_EEPROM_SIZE bytes at most); returns how many.
size_t pb_particle_eeprom(const pb_particle *particle, uint8_t *out, size_t capacity);

// ---- pure functions, for property tests ------------------------------------------------------

uint32_t pb_definition_hash(void);

// A photocell's raw reading (0..1023) as the particle corrects it before averaging, for the
// calibration parameters SENSOR_GAMMA_k = gamma_milli and SENSOR_GAIN_k = gain_milli.
uint16_t pb_calibrated_reading(uint16_t raw, uint16_t gamma_milli, uint16_t gain_milli);

// S_n of a particle reading own_intensity when the others read others[0..others_count) in its
// estimation round. method is the protocol's method enum; the rest are the parameters of the
// same names (GROUPS = 0: one group per particle heard).
uint8_t pb_estimate(uint8_t method, uint16_t own_intensity, const uint16_t *others,
                    size_t others_count, int32_t ref_distance_mm, int32_t ref_value,
                    int32_t diameter_mm, int32_t count_tolerance, int32_t groups);

// Frames one message; returns the frame length, or 0 if it does not fit in capacity or the
// payload exceeds max_payload.
size_t pb_encode_frame(uint8_t type, uint8_t sender, uint8_t seq, const uint8_t *payload,
                       size_t payload_len, uint8_t *out, size_t capacity);

// Runs the firmware's streaming parser over input. Each frame it accepts is written to out as
// [type, sender, seq, payload_len, payload...]; returns the bytes written (a frame that would not
// fit in capacity stops the parse). counters receives rx_frames, rx_bad_crc, rx_bad_length,
// rx_skipped_bytes, as STATUS reports them.
size_t pb_parse_stream(const uint8_t *input, size_t input_len, uint8_t *out, size_t capacity,
                       uint16_t counters[4]);

// ---- firmware constants and the epoch plan, for the vectorised model of the firmware ---------

// Milliseconds per servo step (T = cycle_steps steps).
uint16_t pb_servo_step_ms(void);
// Full-scale reading; a sensor whose mean reads it or 0 is taken as faulty.
uint16_t pb_adc_full_scale(void);
// The largest S_n any method gives.
uint8_t pb_s_n_max(void);

// The epoch a particle plans when its round gives s_n and it heard group_size particles (itself
// included): out[0] first cycle after the common start, out[1] pause t_p, out[2] epoch length,
// all in ms. The other arguments are the run's: START's method, cycle_steps and wave_size (0:
// automatic), the stored WAVE_SIZE, the update interval and ROUND_MS.
void pb_plan_epoch(uint8_t method, uint16_t cycle_steps, uint8_t wave_size, uint8_t wave_size_param,
                   uint32_t update_interval_ms, uint32_t round_ms, uint8_t s_n, uint8_t group_size,
                   uint32_t out[3]);

// ---- what a simulation of the firmware needs to know of it -----------------------------------

// The settings block a particle with this id keeps in EEPROM, written by the firmware's own
// Settings code (layout, defaults, CRC), with params[i] set to values[i] in order, each checked
// as SET_PARAM checks it. Fills out (capacity >= PB_EEPROM_SIZE; the bytes after the block read
// as an erased chip's 0xFF) and returns PB_EEPROM_SIZE. Returns 0 and writes nothing useful when
// the id is not 1..253 (*refused = count) or a value is refused (*refused = its index, *result
// = the ParamResult, e.g. OUT_OF_RANGE).
size_t pb_settings_image(uint8_t id, const uint8_t *params, const int32_t *values, size_t count,
                         uint8_t *out, size_t capacity, size_t *refused, uint8_t *result);

// A partial frame older than this is dropped by the particle's parser (ms without a byte).
uint16_t pb_frame_timeout_ms(void);
// A broadcast request that draws a reply is answered in a random one of pb_ping_slots_unknown()
// slots of pb_ping_slot_ms() each while the particle knows no group size.
uint16_t pb_ping_slot_ms(void);
uint8_t pb_ping_slots_unknown(void);
// Points of the servo calibration table (SERVO_CAL_0..) and the pulses a servo may be given.
uint8_t pb_servo_cal_points(void);
uint16_t pb_servo_pulse_min_us(void);
uint16_t pb_servo_pulse_max_us(void);

#ifdef __cplusplus
}
#endif

#endif  // PARTICLEBOT_PARTICLE_CAPI_H
