/* Message catalogue of the bench protocol (see firmware/PROTOCOL.md, the one written spec).
 * All multi-byte fields are little-endian. A frame body is
 *     type u8 | seq u16 | payload (0..ST_MAX_PAYLOAD bytes) | crc16 u16
 * and goes on the wire COBS-encoded and followed by one 0x00 byte. */
#ifndef ST_PROTO_H
#define ST_PROTO_H
#include <stdint.h>

#define ST_PROTO_VERSION 4u
#define ST_FW_MAJOR 1u
#define ST_FW_MINOR 3u
#define ST_FW_PATCH 0u

#define ST_MAX_PAYLOAD 48u
#define ST_HEADER_LEN 3u
#define ST_CRC_LEN 2u
#define ST_MAX_BODY (ST_HEADER_LEN + ST_MAX_PAYLOAD + ST_CRC_LEN)

/* host -> device */
#define ST_CMD_HELLO 0x01u     /* proto u8 */
#define ST_CMD_ACK 0x02u       /* next_expected u16: cumulative acknowledgement */
#define ST_CMD_NAK 0x03u       /* next_expected u16: acknowledgement + resend from there */
#define ST_CMD_ABORT 0x04u     /* (none) */
#define ST_CMD_CALIBRATE 0x10u /* setpoint_mc i32, settle_ms u32, n u16, interval_ms u16 */
#define ST_CMD_RTH 0x11u       /* power_uw u32, settle_ms u32, window_us u16, n u16 */
#define ST_CMD_COOLING 0x12u   /* power_uw u32, settle_ms u32, window_us u16, n u16,
                                  t_first_us u32, t_last_ms u32, per_decade u8 */
#define ST_CMD_PWM 0x13u       /* power_uw u32, freq_mhz u32, duty_ppm u32, settle_ms u32,
                                  window_us u16, n u16, interval_ms u16 */
#define ST_CMD_FORWARD 0x14u   /* setpoint_mc i32, settle_ms u32, pulse_us u16, n u16,
                                  interval_ms u16, count u8, current_ua u32 x count (v3) */
#define ST_CMD_COUPLING 0x15u  /* heater u8, ports u8, power_uw u32, settle_ms u32, window_us u16,
                                  n u16, t_first_us u32, t_last_ms u32, per_decade u8 (v4) */

/* device -> host */
#define ST_MSG_INFO 0x80u   /* proto u8, fw_major u8, fw_minor u8, fw_patch u8, adc_bits u8,
                               ring u8, caps u16, settle_max_ms u32, i_sense_ua u32 (v3),
                               name (ASCII, rest) */
#define ST_MSG_ACK 0x81u    /* cmd_seq u16, cmd_type u8, status u8 */
#define ST_MSG_SAMPLE 0x82u /* proc u8, kind u8, index u32, t_us u32, v_tsp_uv i32, v_d_uv i32,
                               i_ua i32, tamb_mc i32, taux_mc i32, code[5] u16 */
#define ST_MSG_STATUS 0x83u /* proc u8, state u8, done u16, total u16, elapsed_ms u32 */
#define ST_MSG_DONE 0x84u   /* proc u8, status u8, n_samples u16, first_index u32 */
#define ST_MSG_SYNC 0x85u   /* unsequenced (seq = device next_seq): last_cmd_seq u16, busy u8 */
#define ST_MSG_ERROR 0x86u  /* code u8, detail u16 */
#define ST_MSG_ARRAY_SAMPLE 0x87u /* SAMPLE's payload, then port u8 (the coupling procedure) */

#define ST_LEN_SAMPLE 40u
#define ST_LEN_ARRAY_SAMPLE 41u
#define ST_LEN_INFO_FIXED 16u
#define ST_LEN_FORWARD_FIXED 15u
#define ST_FORWARD_MAX 8u /* currents of one FORWARD command */
#define ST_LEN_COUPLING 23u

/* Limits the device enforces (a longer time is refused with ST_E_PARAM). Settling is timed in
 * milliseconds, immune to the 32-bit microsecond clock's wrap; ST_SETTLE_MAX_MS is reported
 * in INFO. Cooling-curve instants are absolute clock times compared by signed difference, so
 * the curve must end within 2^31 us (2147 s) of the cut. */
#define ST_SETTLE_MAX_MS 86400000UL /* 24 h */
#define ST_CURVE_MAX_MS 2000000UL   /* 2000 s */

/* ACK status */
#define ST_OK 0u
#define ST_E_BUSY 1u
#define ST_E_LENGTH 2u
#define ST_E_PARAM 3u
#define ST_E_UNKNOWN 4u

/* ERROR codes */
#define ST_ERR_LOST 1u     /* NAK asked for a frame no longer in the ring: detail = seq */
#define ST_ERR_OVERFLOW 2u /* sample FIFO overflowed: detail = samples dropped */
#define ST_ERR_NAK_RANGE 3u /* NAK for a frame never sent: detail = seq */

/* procedures */
#define ST_PROC_NONE 0u
#define ST_PROC_CAL 1u
#define ST_PROC_RTH 2u
#define ST_PROC_COOLING 3u
#define ST_PROC_PWM 4u
#define ST_PROC_FORWARD 5u
#define ST_PROC_COUPLING 6u

/* sample kinds */
#define ST_KIND_CURVE 0u   /* cooling-curve point; t_us from the cut */
#define ST_KIND_STEADY 1u  /* steady reading at the end of a sample window; t_us = window */
#define ST_KIND_CAL 2u     /* calibration reading (heater off); t_us from the reading start */
#define ST_KIND_POWER 3u   /* on-phase reading (heater current and voltage); t_us = 0 */
#define ST_KIND_FORWARD 4u /* forward-voltage reading in a current pulse; t_us from its start */
#define ST_KIND_COLD 5u    /* coupling: every heater off, before heating; t_us from the start */

/* capability bits of INFO.caps */
#define ST_CAP_IDEAL_HOLD 0x0001u /* the TSP is held at the window start (no window cooling) */
#define ST_CAP_PORTS_SHIFT 8u     /* bits 8..15: heaters of an array board (0: one heater) */

/* ADC channels: the sequencer converts all five at the same instant */
#define ST_CH_TSP 0u  /* INA output: Voff + G (Vref_diode - Vd) */
#define ST_CH_VD 1u   /* heater diode voltage (buffered) */
#define ST_CH_ID 2u   /* heater current: sense-resistor amplifier */
#define ST_CH_TAMB 3u /* reference thermocouple amplifier (ambient, or case/heatsink) */
#define ST_CH_TAUX 4u /* auxiliary thermocouple (on the device during calibration) */
#define ST_NCH 5u

static inline void st_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static inline void st_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static inline uint16_t st_get_u16(const uint8_t *p)
{
    return (uint16_t)(p[0] | ((uint16_t)p[1] << 8));
}
static inline uint32_t st_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

#endif
