/* Host (software-in-the-loop) hardware layer. Each simulated device is an hh_device_t; the
 * core's HAL calls are recorded as an ordered list of operations, with the time they were
 * made, for the driver (spicethermal/bench/simulator.py, via ctypes) to apply to its plant.
 * The driver sets the clock, feeds received bytes and ADC results, calls hh_poll and drains
 * the operations and the transmitted bytes. */
#ifndef HAL_HOST_H
#define HAL_HOST_H
#include <stdint.h>
#include "st_core.h"
#include "st_hal.h"

#define HH_MAX_OPS 64u
#define HH_TX_LEN 16384u

enum {
    HH_OP_DAC = 1,           /* a = code */
    HH_OP_PWM = 2,           /* a = period_ns, b = on_ns */
    HH_OP_CUT = 3,           /* a = at_on_end */
    HH_OP_RELEASE = 4,
    HH_OP_ADC_AT = 5,        /* a = t_us */
    HH_OP_ADC_AFTER_CUT = 6, /* a = delay_us */
    HH_OP_ADC_ON_PHASE = 7,
    HH_OP_FIXTURE = 8,       /* a = code */
    HH_OP_HEATER = 9,        /* a = heater of an array board */
    HH_OP_TSP = 10           /* a = TSP diode of an array board */
};

typedef struct {
    uint32_t op, a, b, t_us;
} hh_op_t;

typedef struct {
    /* set by the driver */
    uint32_t now_us;
    st_board_t board;
    /* set by the core through the HAL */
    uint32_t wake_us;
    uint32_t wake_set;
    uint32_t n_ops;
    uint32_t ops_lost;
    hh_op_t ops[HH_MAX_OPS];
    uint32_t tx_len;
    uint8_t tx[HH_TX_LEN];
} hh_state_t;

typedef struct {
    hh_state_t s; /* first member: the driver maps it with ctypes */
    st_core_t core;
} hh_device_t;

hh_device_t *hh_new(void);
void hh_free(hh_device_t *d);
void hh_init(hh_device_t *d);
void hh_rx(hh_device_t *d, const uint8_t *buf, uint32_t n);
void hh_adc(hh_device_t *d, const uint16_t *code);
void hh_poll(hh_device_t *d);
uint32_t hh_busy(hh_device_t *d);
/* 1 when samples wait for room in the transmit ring (the host has not acknowledged enough):
 * the simulator then lets the host catch up before advancing simulated time. */
uint32_t hh_blocked(hh_device_t *d);
/* firmware version reported in INFO (tests fake an old firmware with it) */
void hh_set_version(uint8_t major, uint8_t minor, uint8_t patch);

#endif
