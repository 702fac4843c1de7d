/* CRC-16/CCITT-FALSE (a.k.a. CRC-16/IBM-3740): poly 0x1021, init 0xFFFF, no reflection,
 * no final xor. Check value: crc16("123456789") == 0x29B1. */
#ifndef ST_CRC16_H
#define ST_CRC16_H
#include <stdint.h>
#include <stddef.h>

#define ST_CRC16_INIT 0xFFFFu

uint16_t st_crc16_update(uint16_t crc, uint8_t byte);
uint16_t st_crc16(const uint8_t *data, size_t n);

#endif
