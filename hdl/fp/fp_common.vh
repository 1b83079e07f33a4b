// Shared functions of the IEEE 754 binary32 units (fp_add, fp_mul, fp_div).
//
// Included inside each module body (Verilog-2005 functions belong to a
// module), so this file has no include guard.
//
// The adder and the multiplier take a word as encoded (fp_exp1, fp_sig24:
// a subnormal is its fraction at exponent 1). The divider unpacks into an
// internal format: a signed 12-bit biased exponent e and a significand m
// whose leading one sits at a fixed bit, value m / 2^(top bit) *
// 2^(e - 127). Subnormal inputs are normalised on unpack (their e goes
// below 1); results with e below 1 are shifted back into the subnormal
// range by fp_round_pack (gradual underflow).

// Canonical quiet NaN: every NaN result of the units is this word.
localparam [31:0] FP_QNAN = 32'h7FC0_0000;

// The biased exponent of a finite word as encoded, a subnormal's (and a
// zero's) taken as 1.
function [7:0] fp_exp1;
    input [31:0] x;
    fp_exp1 = (x[30:23] == 8'd0) ? 8'd1 : x[30:23];
endfunction

// The significand of a finite word as encoded: the fraction with its
// hidden bit, 0 for a subnormal.
function [23:0] fp_sig24;
    input [31:0] x;
    fp_sig24 = {x[30:23] != 8'd0, x[22:0]};
endfunction

// Leading zeros of a 24-bit vector (24 for zero), by binary search
// (halving steps rather than a priority chain).
function [4:0] fp_lzc24;
    input [23:0] x;
    reg [31:0] v;
    reg [4:0] n;
    begin
        v = {x, 8'hFF};  // the ones stop the search at 24 for a zero x
        n = 5'd0;
        if (v[31:16] == 16'd0) begin n = n + 5'd16; v = v << 16; end
        if (v[31:24] == 8'd0)  begin n = n + 5'd8;  v = v << 8;  end
        if (v[31:28] == 4'd0)  begin n = n + 5'd4;  v = v << 4;  end
        if (v[31:30] == 2'd0)  begin n = n + 5'd2;  v = v << 2;  end
        if (v[31] == 1'b0)     n = n + 5'd1;
        fp_lzc24 = n;
    end
endfunction

// Trailing zeros of a 24-bit vector (24 for zero): the leading zeros of
// its bits reversed.
function [4:0] fp_tzc24;
    input [23:0] x;
    reg [23:0] r;
    integer i;
    begin
        for (i = 0; i < 24; i = i + 1)
            r[i] = x[23 - i];
        fp_tzc24 = fp_lzc24(r);
    end
endfunction

// Leading zeros of a 28-bit vector (28 for zero), likewise.
function [4:0] fp_lzc28;
    input [27:0] x;
    reg [31:0] v;
    reg [4:0] n;
    begin
        v = {x, 4'hF};
        n = 5'd0;
        if (v[31:16] == 16'd0) begin n = n + 5'd16; v = v << 16; end
        if (v[31:24] == 8'd0)  begin n = n + 5'd8;  v = v << 8;  end
        if (v[31:28] == 4'd0)  begin n = n + 5'd4;  v = v << 4;  end
        if (v[31:30] == 2'd0)  begin n = n + 5'd2;  v = v << 2;  end
        if (v[31] == 1'b0)     n = n + 5'd1;
        fp_lzc28 = n;
    end
endfunction

// Unpacks a finite nonzero word into {e[11:0], m[23:0]} with m[23] = 1:
// a subnormal's significand is shifted left by its leading-zero count and
// its exponent lowered by as much (1 - lz). Zeros, infinities and NaNs are
// classified by the callers from the raw word.
function [35:0] fp_unpack;
    input [31:0] x;
    reg [23:0] m;
    reg [4:0] lz;
    begin
        if (x[30:23] != 8'd0)
            fp_unpack = {4'd0, x[30:23], 1'b1, x[22:0]};
        else begin
            m = {1'b0, x[22:0]};
            lz = fp_lzc24(m);
            fp_unpack = {12'd1 - {7'd0, lz}, m << lz};
        end
    end
endfunction

// Rounds to nearest, ties to even, and packs. s: sign; e: signed biased
// exponent of m[26]; m: significand with m[26] = 1 (or m = 0 for a zero of
// sign s), m[25:3] the fraction, m[2] the guard bit and m[1:0] lower bits
// whose OR is the sticky bit (a caller folds any discarded nonzero bits
// into m[0]). e >= 255 gives an infinity; e <= 0 shifts m right by 1 - e
// into the subnormal range, OR-ing the bits shifted out into the sticky
// bit. The rounding increment is added to the packed {exponent, fraction},
// so a carry out of the fraction moves a subnormal to the smallest normal
// and the largest finite to infinity.
function [31:0] fp_round_pack;
    input s;
    input signed [11:0] e;
    input [26:0] m;
    reg [26:0] t;
    reg [11:0] sh;
    reg lost;
    reg [7:0] ef;
    reg inc;
    reg [30:0] mag;
    begin
        if (e >= 12'sd255)
            fp_round_pack = {s, 8'hFF, 23'd0};
        else begin
            if (e <= 12'sd0) begin
                sh = 12'd1 - e;
                if (sh > 12'd27) begin
                    t = 27'd0;
                    lost = |m;
                end else begin
                    t = m >> sh;
                    lost = ((t << sh) != m);
                end
                ef = 8'd0;
            end else begin
                t = m;
                lost = 1'b0;
                ef = e[7:0];
            end
            inc = t[2] & (t[3] | t[1] | t[0] | lost);
            mag = {ef, t[25:3]} + {30'd0, inc};
            fp_round_pack = {s, mag};
        end
    end
endfunction
