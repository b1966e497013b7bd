/* HMAC-SHA256 (RFC 2104 over FIPS 180-4's SHA-256): what authenticates a live input's datagram
 * when the run has a key (realtime.c). Checked against Python's hmac module in the tests. */
#include <stdint.h>
#include <string.h>

#include "kernel.h"

typedef struct {
    uint32_t state[8];
    uint64_t length; /* bytes hashed */
    unsigned char block[64];
    size_t used;
} Sha256;

static const uint32_t K[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98,
    0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786,
    0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8,
    0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13,
    0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819,
    0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a,
    0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
    0xc67178f2};

static uint32_t rotate(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

static void compress(Sha256 *c, const unsigned char *b) {
    uint32_t w[64], s[8];
    for (int i = 0; i < 16; i++)
        w[i] = (uint32_t)b[4 * i] << 24 | (uint32_t)b[4 * i + 1] << 16 | (uint32_t)b[4 * i + 2] << 8 | b[4 * i + 3];
    for (int i = 16; i < 64; i++) {
        const uint32_t s0 = rotate(w[i - 15], 7) ^ rotate(w[i - 15], 18) ^ (w[i - 15] >> 3);
        const uint32_t s1 = rotate(w[i - 2], 17) ^ rotate(w[i - 2], 19) ^ (w[i - 2] >> 10);
        w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    memcpy(s, c->state, sizeof s);
    for (int i = 0; i < 64; i++) {
        const uint32_t t1 = s[7] + (rotate(s[4], 6) ^ rotate(s[4], 11) ^ rotate(s[4], 25)) +
                            ((s[4] & s[5]) ^ (~s[4] & s[6])) + K[i] + w[i];
        const uint32_t t2 = (rotate(s[0], 2) ^ rotate(s[0], 13) ^ rotate(s[0], 22)) +
                            ((s[0] & s[1]) ^ (s[0] & s[2]) ^ (s[1] & s[2]));
        memmove(s + 1, s, 7 * sizeof s[0]);
        s[4] += t1;
        s[0] = t1 + t2;
    }
    for (int i = 0; i < 8; i++) c->state[i] += s[i];
}

static void sha256_start(Sha256 *c) {
    static const uint32_t initial[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                        0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    memcpy(c->state, initial, sizeof initial);
    c->length = 0;
    c->used = 0;
}

static void sha256_add(Sha256 *c, const unsigned char *data, size_t size) {
    c->length += size;
    while (size > 0) {
        const size_t take = size < 64 - c->used ? size : 64 - c->used;
        memcpy(c->block + c->used, data, take);
        c->used += take;
        data += take;
        size -= take;
        if (c->used == 64) {
            compress(c, c->block);
            c->used = 0;
        }
    }
}

static void sha256_end(Sha256 *c, unsigned char digest[32]) {
    const uint64_t bits = c->length * 8;
    const unsigned char one = 0x80, zero = 0;
    sha256_add(c, &one, 1);
    while (c->used != 56) sha256_add(c, &zero, 1);
    unsigned char size[8];
    for (int i = 0; i < 8; i++) size[i] = (unsigned char)(bits >> (56 - 8 * i));
    sha256_add(c, size, 8);
    for (int i = 0; i < 8; i++)
        for (int j = 0; j < 4; j++) digest[4 * i + j] = (unsigned char)(c->state[i] >> (24 - 8 * j));
}

void hmac_sha256(const unsigned char *key, size_t key_size, const unsigned char *message, size_t size,
                 unsigned char tag[32]) {
    unsigned char block[64] = {0}, pad[64], inner[32];
    Sha256 c;
    if (key_size > 64) {
        sha256_start(&c);
        sha256_add(&c, key, key_size);
        sha256_end(&c, block);
    } else if (key_size > 0) {
        memcpy(block, key, key_size);
    }
    for (int i = 0; i < 64; i++) pad[i] = block[i] ^ 0x36;
    sha256_start(&c);
    sha256_add(&c, pad, 64);
    sha256_add(&c, message, size);
    sha256_end(&c, inner);
    for (int i = 0; i < 64; i++) pad[i] = block[i] ^ 0x5c;
    sha256_start(&c);
    sha256_add(&c, pad, 64);
    sha256_add(&c, inner, 32);
    sha256_end(&c, tag);
}
