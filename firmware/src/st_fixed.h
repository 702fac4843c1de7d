/* Fixed-point helpers of the core: log-spaced sample times and ADC code conversions. No
 * floating point and no 64-bit arithmetic (the PIC18 build has neither cheaply). */
#ifndef ST_FIXED_H
#define ST_FIXED_H
#include <stdint.h>
#include "st_hal.h"

/* 10^(m/1000) in Q12 (4096 = 1.0) for 0 <= m < 1000; max relative error 2e-4. */
uint16_t st_pow10_milli_q12(uint16_t m);

/* k-th time of a log-spaced schedule, t_first_us * 10^(k / per_decade), in us; saturates
 * at 0xFFFFFFFF. Times of consecutive k are strictly increasing while t_first_us >= 100. */
uint32_t st_log_time_us(uint32_t t_first_us, uint8_t per_decade, uint16_t k);

/* Number of points of the schedule with t <= t_last_us. */
uint16_t st_log_count(uint32_t t_first_us, uint8_t per_decade, uint32_t t_last_us);

/* Channel conversion (rounded to nearest). */
int32_t st_convert(const st_conv_t *c, uint16_t code);

/* Heater current (uA) that dissipates power_uw at a diode voltage of vd_uv. */
uint32_t st_current_for_power(uint32_t power_uw, uint32_t vd_uv);

/* DAC code for a current, clamped to [0, dac_max]. */
uint16_t st_dac_for_current(uint32_t i_ua, uint32_t i_full_ua, uint16_t dac_max);

/* PWM period and on-time in ns from frequency (mHz) and duty (ppm). */
uint32_t st_period_ns(uint32_t freq_mhz);
uint32_t st_on_ns(uint32_t period_ns, uint32_t duty_ppm);

#endif
