// IEEE 754 binary32 multiplier: y = a * b.
//
// Round to nearest, ties to even; subnormal inputs and results (gradual
// underflow); the sign of a product is the XOR of the operands' signs,
// zeros included; any NaN operand or 0 * inf gives the canonical quiet NaN
// 0x7FC00000. Pipelined with latency `FP_MUL_LAT (3, see fp_latency.vh for
// the edge at which y appears), one operation per clock:
//   stage 0: the operands registered;
//   stage 1: classify; the 24x24 product of the significands as encoded
//            (a subnormal's hidden bit 0), and beside it where its 27
//            result bits lie;
//   stage 2: take those bits by one shift, round, pack.
//
// The significands enter the multiplier as encoded, so no normalisation
// stands between the operand registers and the DSP blocks. Beside the
// product, stage 1 finds from the operands alone everything the shift
// needs: the product p of significands ma, mb has its leading one at bit
// 47 - lz or 46 - lz (lz the significands' leading zeros, nonzero only for
// a subnormal), its bit 46 weighs 2^(e - 127) with e = ea + eb - 127, and
// its trailing zeros are those of ma and mb together, which give the
// sticky bit without looking at the bits shifted out.
`include "fp_latency.vh"

module fp_mul (
    input  wire        clk,
    input  wire [31:0] a_in,
    input  wire [31:0] b_in,
    output wire [31:0] y
);
`include "fp_common.vh"

    // ---- stage 0: the operands registered (fp_latency.vh says why) ----
    reg [31:0] a;
    reg [31:0] b;
    always @(posedge clk) begin
        a <= a_in;
        b <= b_in;
    end

    // Each stage is one clocked block: its combinational logic is written
    // with blocking assignments to temporaries (assigned before use on every
    // path, so they synthesise to wires) and its results go to the stage's
    // registers. This also evaluates each stage once per clock in a
    // simulator.

    // Operand classes.
    wire a_nan = (a[30:23] == 8'hFF) && (a[22:0] != 23'd0);
    wire b_nan = (b[30:23] == 8'hFF) && (b[22:0] != 23'd0);
    wire a_inf = (a[30:0] == 31'h7F80_0000);
    wire b_inf = (b[30:0] == 31'h7F80_0000);
    wire a_zero = (a[30:0] == 31'd0);
    wire b_zero = (b[30:0] == 31'd0);

    // Exponents (a subnormal's is 1) and significands as encoded.
    wire [7:0]  ea = fp_exp1(a);
    wire [7:0]  eb = fp_exp1(b);
    wire [23:0] ma = fp_sig24(a);
    wire [23:0] mb = fp_sig24(b);

    // ---- stage 1 ----
    // The result's 27 bits m (m[26] its leading one, or 0 for a subnormal;
    // m[2] the guard bit; m[0] the sticky bit) are bits T..T-26 of p: by
    // default T = 47 - sl, where sl = min(lz, e) (p shifted left by sl,
    // right by -sl when e <= 0: never below exponent 1). When lz < e and the
    // product's leading one turns out to sit at 46 - lz, one bit lower
    // (T = 46 - sl).
    reg               r1_special;  // a NaN, an infinity or a zero operand
    reg        [31:0] r1_spec_y;   // the result then
    reg               r1_s;
    reg        [47:0] r1_p;        // product of the significands
    reg        [6:0]  r1_r;        // p's shift: right by r1_r from {p, 24'b0}
    reg               r1_low;      // lz < e: one bit lower if p[47 - lz] = 0
    reg        [8:0]  r1_sum;      // ea + eb (e = sum - 127)
    reg        [4:0]  r1_lz;       // the subnormal operand's leading zeros
    reg        [5:0]  r1_tz;       // p's trailing zeros

    // e = sum - 127. Only a subnormal significand has leading zeros, and
    // with two subnormal operands e = -125 is below any lz, so lz is the OR
    // of the two counts wherever it is used. "e <= lz" is then sum <= 127,
    // or sum - 127 (found beside the count) <= lz: one carry chain after
    // the count.
    wire [8:0] s1_sum = {1'b0, ea} + {1'b0, eb};
    wire [8:0] s1_e1  = s1_sum - 9'd127;
    wire [4:0] s1_lz  = fp_lzc24(ma) | fp_lzc24(mb);
    // sl = e (e <= lz: down to exponent 1 at most) or lz.
    wire       s1_le  = s1_sum <= 9'd127 || s1_e1 <= {4'd0, s1_lz};
    always @(posedge clk) begin
        r1_s   <= a[31] ^ b[31];
        r1_p   <= ma * mb;
        // r = 24 - sl: 151 - sum when sl = e (saturated at 127: sum < 24
        // shifts every bit out), else 24 - lz.
        r1_r   <= s1_le ? ((s1_sum < 9'd24) ? 7'd127 : 7'd23 - s1_sum[6:0])
                        : 7'd24 - {2'd0, s1_lz};
        r1_low <= !s1_le;
        r1_sum <= s1_sum;
        r1_lz  <= s1_lz;
        r1_tz  <= {1'b0, fp_tzc24(ma)} + {1'b0, fp_tzc24(mb)};

        r1_special <= 1'b1;
        if (a_nan || b_nan || (a_inf && b_zero) || (a_zero && b_inf))
            r1_spec_y <= FP_QNAN;
        else if (a_inf || b_inf)
            r1_spec_y <= {a[31] ^ b[31], 8'hFF, 23'd0};
        else if (a_zero || b_zero)
            r1_spec_y <= {a[31] ^ b[31], 31'd0};
        else begin
            r1_special <= 1'b0;
            r1_spec_y  <= 32'd0;
        end
    end

    // ---- stage 2 ----
    reg        [31:0] r2_y;

    reg        [71:0] s2_q;   // bits 47..21: p's bits 47 - sl .. 21 - sl
    reg               s2_b;   // the leading one is one bit lower
    reg        [26:0] s2_m;
    reg        [7:0]  s2_ef;
    reg               s2_inc;
    reg        [30:0] s2_mag;
    // Beside the shift, from the registered sums: the exponent fields
    // e + 1 - lz and e - lz when sl = lz (sum - lz - 126 and - 127; 1 and 0
    // when sl = e, where the leading one can be at bit 47 - sl only at
    // exponent 1), their overflow, and the sticky bit, p's trailing zeros
    // against T - 26 (tz + sl <= 21, or <= 20 one bit lower).
    wire [7:0] s2_ea  = r1_low ? r1_sum[7:0] - {3'd0, r1_lz} - 8'd126 : 8'd1;
    wire [7:0] s2_eb  = r1_low ? r1_sum[7:0] - {3'd0, r1_lz} - 8'd127 : 8'd0;
    wire       s2_ova = r1_low && {1'b0, r1_sum} >= {5'd0, r1_lz} + 10'd381;
    wire       s2_ovb = r1_low && {1'b0, r1_sum} >= {5'd0, r1_lz} + 10'd382;
    wire       s2_sta = r1_low ? {1'b0, r1_tz} + {2'd0, r1_lz} <= 7'd21
                               : {1'b0, r1_sum} + {4'd0, r1_tz} <= 10'd148;
    wire       s2_stb = r1_low ? {1'b0, r1_tz} + {2'd0, r1_lz} <= 7'd20
                               : {1'b0, r1_sum} + {4'd0, r1_tz} <= 10'd147;
    always @(posedge clk) begin
        s2_q = {r1_p, 24'd0} >> r1_r;
        s2_b = !s2_q[47] && r1_low;
        s2_m = s2_b ? {s2_q[46:21], s2_stb} : {s2_q[47:22], s2_sta};
        // The exponent field: 0 for a subnormal (no leading one at bit 47
        // and none one lower to take).
        s2_ef = s2_q[47] ? s2_ea : (r1_low ? s2_eb : 8'd0);
        s2_inc = s2_m[2] & (s2_m[3] | s2_m[1] | s2_m[0]);
        // A carry out of the fraction moves a subnormal to the smallest
        // normal, and the largest finite to infinity.
        s2_mag = {s2_ef, s2_m[25:3]} + {30'd0, s2_inc};
        if (r1_special)
            r2_y <= r1_spec_y;
        else if (s2_b ? s2_ovb : s2_ova)
            r2_y <= {r1_s, 8'hFF, 23'd0};
        else
            r2_y <= {r1_s, s2_mag};
    end

    assign y = r2_y;
endmodule
