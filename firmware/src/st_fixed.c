#include "st_fixed.h"

uint16_t st_pow10_milli_q12(uint16_t m)
{
    /* 10^x = 2^(x log2 10); e = m * log2(10) / 1000 in Q16 (217706 = log2(10) * 65536). */
    uint32_t e = ((uint32_t)m * 217706U + 500U) / 1000U;
    uint8_t ip = (uint8_t)(e >> 16);
    uint32_t f = e & 0xFFFFU; /* Q16 fraction */
    /* 2^f on [0,1): 1 + f (0.69583 + f (0.22606 + f 0.07811)), max error 1e-4 */
    uint32_t p = 5119U;                        /* 0.07811 Q16 */
    p = 14815U + ((p * f) >> 16);               /* 0.22606 */
    p = 45602U + ((p * f) >> 16);               /* 0.69583 */
    p = 65536U + ((p * f) >> 16);               /* Q16, < 2^17 */
    /* result Q12 = p * 2^ip / 16 */
    return (uint16_t)((p << ip) >> 4);
}

uint32_t st_log_time_us(uint32_t t_first_us, uint8_t per_decade, uint16_t k)
{
    uint16_t dec, m;
    uint32_t t = t_first_us, hi, lo;
    uint16_t q;
    if (per_decade == 0) {
        return t_first_us;
    }
    dec = (uint16_t)(k / per_decade);
    m = (uint16_t)(((uint32_t)(k % per_decade) * 1000U) / per_decade);
    while (dec--) {
        if (t > 429496729U) {
            return 0xFFFFFFFFU;
        }
        t *= 10U;
    }
    q = st_pow10_milli_q12(m);
    hi = (t >> 12) * q;
    lo = ((t & 0xFFFU) * q + 2048U) >> 12;
    if ((t >> 12) && hi / (t >> 12) != q) {
        return 0xFFFFFFFFU;
    }
    if (hi > 0xFFFFFFFFU - lo) {
        return 0xFFFFFFFFU;
    }
    return hi + lo;
}

uint16_t st_log_count(uint32_t t_first_us, uint8_t per_decade, uint32_t t_last_us)
{
    uint16_t k = 0;
    while (k < 0xFFFFu && st_log_time_us(t_first_us, per_decade, k) <= t_last_us) {
        if (st_log_time_us(t_first_us, per_decade, k) == 0xFFFFFFFFU) {
            break;
        }
        k++;
    }
    return k;
}

int32_t st_convert(const st_conv_t *c, uint16_t code)
{
    int32_t x = (int32_t)code * c->num + c->off;
    int32_t half = c->den / 2;
    if (c->den <= 0) {
        return 0;
    }
    return x >= 0 ? (x + half) / c->den : -((-x + half) / c->den);
}

uint32_t st_current_for_power(uint32_t power_uw, uint32_t vd_uv)
{
    /* i_ua = power_uw / (vd_uv / 1e6); computed as power_uw * 1000 / vd_mv in two steps */
    uint32_t vd_mv = (vd_uv + 500U) / 1000U;
    uint32_t q, r;
    if (vd_mv == 0) {
        return 0;
    }
    q = power_uw / vd_mv;
    r = power_uw % vd_mv;
    if (q > 4000000U) {
        return 0xFFFFFFFFU;
    }
    return q * 1000U + (r * 1000U) / vd_mv;
}

uint16_t st_dac_for_current(uint32_t i_ua, uint32_t i_full_ua, uint16_t dac_max)
{
    /* code = i * dac_max / i_full, avoiding overflow: scale both to at most 2^20 */
    uint32_t num = i_ua, den = i_full_ua, code;
    if (den == 0) {
        return 0;
    }
    while (num > 0xFFFFFU || den > 0xFFFFFU) {
        num >>= 1;
        den >>= 1;
    }
    if (den == 0) {
        return dac_max;
    }
    code = (num * dac_max + den / 2) / den;
    return code > dac_max ? dac_max : (uint16_t)code;
}

uint32_t st_period_ns(uint32_t freq_mhz)
{
    /* 1e12 / freq_mhz by long division (valid up to 429 kHz) */
    uint32_t q, rem;
    uint8_t i;
    if (freq_mhz == 0 || freq_mhz > 429496729U) {
        return 0;
    }
    q = 1000000000U / freq_mhz;
    rem = 1000000000U % freq_mhz;
    for (i = 0; i < 3; i++) {
        if (q > 429496728U) {
            return 0xFFFFFFFFU;
        }
        rem *= 10U;
        q = q * 10U + rem / freq_mhz;
        rem %= freq_mhz;
    }
    return q;
}

uint32_t st_on_ns(uint32_t period_ns, uint32_t duty_ppm)
{
    /* period_ns * duty_ppm / 1e6 in 32-bit pieces */
    uint32_t hi = period_ns / 1000000U, lo = period_ns % 1000000U, on;
    if (duty_ppm >= 1000000U) {
        return period_ns;
    }
    on = hi * duty_ppm + (lo * (duty_ppm / 1000U)) / 1000U
         + (lo * (duty_ppm % 1000U)) / 1000000U;
    return on > period_ns ? period_ns : on;
}
