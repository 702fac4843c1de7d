/* The portable core of the bench firmware: command handling, the four measurement procedures
 * as state machines, the sample FIFO and the device side of the link. It touches hardware only
 * through st_hal.h and is driven by three entry points:
 *   st_core_rx_byte()  - every received UART byte (UART receive interrupt or main loop)
 *   st_core_adc_done() - the result of the armed ADC conversion (ADC interrupt)
 *   st_core_poll()     - the main loop, at least at the time last given to hal_wake_at() */
#ifndef ST_CORE_H
#define ST_CORE_H
#include <stdint.h>
#include "st_link.h"

#ifndef ST_FIFO_LEN
#define ST_FIFO_LEN 32u
#endif
#define ST_CONTROL_TICK_MS 100u /* power regulation period while heating */
#define ST_STATUS_MS 1000u      /* heartbeat period of STATUS frames during long waits */
/* ring slots kept free of samples and heartbeats, for ACK and DONE */
#define ST_RESERVE (ST_RING_FRAMES >= 16u ? 3u : 1u)

typedef struct {
    uint8_t kind;
    uint8_t port; /* the TSP diode read (array boards; 0 otherwise) */
    uint32_t t_us;
    uint16_t code[ST_NCH];
} st_raw_t;

typedef struct {
    /* command parameters */
    uint8_t proc;
    uint32_t power_uw, settle_ms, t_first_us, t_last_ms, period_ns, on_ns;
    uint16_t window_us, n, interval_ms;
    uint8_t per_decade;
    int32_t setpoint_mc;
    uint16_t dac[ST_FORWARD_MAX]; /* FORWARD: the currents' DAC codes */
    uint8_t count;
    /* state machine */
    uint8_t state;
    uint32_t t_start, t_next, t_status, t_cut;
    uint32_t t_clock, run_ms, run_us; /* time since t_start: run_ms + run_us / 1000 ms */
    uint16_t k, total;
    uint8_t adc_armed, adc_ready, adc_kind;
    uint32_t adc_t_us;
    uint16_t codes[ST_NCH];
    uint16_t n_samples;
    uint32_t first_index;
    uint8_t status;
    /* coupling (array boards): the heated port, the ports read, the scan in progress */
    uint8_t heater, ports, port, scan_kind, scan_then;
    uint32_t scan_base, scan_rel;
} st_proc_t;

typedef struct {
    st_rx_t rx;
    st_ring_t ring;
    uint16_t last_cmd_seq;
    uint8_t have_cmd;
    uint32_t sample_index;
    st_raw_t fifo[ST_FIFO_LEN];
    uint8_t f_head, f_count;
    uint16_t f_dropped;
    st_proc_t p;
    uint8_t pending_sync; /* unsequenced SYNC owed to the host */
    uint8_t ack_pending;  /* an ACK waiting for room in the ring */
    uint8_t ack[4];
    uint8_t pending_err, pending_err_code;
    uint16_t pending_err_detail;
    uint8_t wire[ST_WIRE_MAX];
} st_core_t;

/* Version reported in INFO; the host build lets tests change it to fake old firmware. */
extern uint8_t st_fw_version[3];

void st_core_init(st_core_t *c);
void st_core_rx_byte(st_core_t *c, uint8_t byte);
void st_core_adc_done(st_core_t *c, const uint16_t code[ST_NCH]);
void st_core_poll(st_core_t *c);
/* 1 while a procedure runs */
uint8_t st_core_busy(const st_core_t *c);

#endif
