/* The hardware layer the portable core runs on. Two implementations: hal/pic18f4431 (XC8,
 * the bench) and hal/host (gcc; the simulated bench drives it from Python via ctypes).
 *
 * Time is a free-running 32-bit microsecond counter; the core only ever compares times by
 * signed difference, so it may wrap (every 71.6 min). ADC conversions are asynchronous: the
 * core arms one conversion of all ST_NCH channels (hardware-triggered at an exact instant) and
 * the result arrives through st_core_adc_done(). */
#ifndef ST_HAL_H
#define ST_HAL_H
#include <stdint.h>
#include "st_proto.h"

/* Linear conversion of one ADC channel to a fixed-point physical value:
 *     value = (code * num + off) / den          (int32 arithmetic, code <= 1023)
 * units: ST_CH_TSP uV (Vd - Vref, at the INA input), ST_CH_VD uV, ST_CH_ID uA,
 *        ST_CH_TAMB and ST_CH_TAUX milli-degC. */
typedef struct {
    int32_t num;
    int32_t off;
    int32_t den;
} st_conv_t;

typedef struct {
    st_conv_t ch[ST_NCH];
    uint32_t i_full_ua;    /* heater current at DAC full scale */
    uint16_t dac_max;      /* heater current DAC full-scale code */
    uint32_t vd_nominal_uv;/* heater voltage assumed before the first power reading */
    int32_t fixture_min_mc;/* calibration fixture setpoint at code 0 */
    int32_t fixture_max_mc;/* ... and at code dac_max */
    uint16_t caps;         /* ST_CAP_* bits reported in INFO */
    uint8_t adc_bits;
    char name[16];
    uint32_t i_sense_ua;   /* the sense (calibration) current of block B, reported in INFO */
    uint8_t ports;         /* heaters (and TSP diodes) of an array board; 0 or 1: one */
    uint16_t scan_us;      /* array board: multiplexer settling + conversion per port */
} st_board_t;

const st_board_t *hal_board(void);
uint32_t hal_now_us(void);
/* Call st_core_poll() no later than t_us (the core may be polled earlier). */
void hal_wake_at(uint32_t t_us);

/* Heater: constant-current source (DAC code) switched by the power-control PWM.
 * period_ns == 0: heater off. on_ns >= period_ns: heater on continuously. The PWM time base
 * restarts on every call, with an on-phase first. */
void hal_heater_dac(uint16_t code);
void hal_heater_pwm(uint32_t period_ns, uint32_t on_ns);
/* Force the heater off (output override): now (at_on_end = 0) or when the current or next
 * on-phase ends (at_on_end = 1). hal_release() ends the override. */
void hal_cut(uint8_t at_on_end);
void hal_release(void);

/* ADC: arm one conversion (all channels, simultaneous sample-and-hold). */
void hal_adc_at(uint32_t t_us);            /* at an absolute time */
void hal_adc_after_cut(uint32_t delay_us); /* delay_us after the (pending) cut instant */
void hal_adc_on_phase(void);               /* in the middle of the next on-phase */

/* Array board (ports > 1): route the heater current source to heater `port`, and the TSP
 * amplifier's input multiplexer to diode `port` (settled within scan_us). */
void hal_select_heater(uint8_t port);
void hal_select_tsp(uint8_t port);

/* Calibration fixture (hot plate with its own controller): setpoint DAC. */
void hal_fixture_dac(uint16_t code);

/* UART: space in the transmit buffer and a non-blocking write of n <= space bytes. */
uint16_t hal_uart_space(void);
void hal_uart_write(const uint8_t *buf, uint16_t n);

#endif
