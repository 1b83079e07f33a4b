// Testbench of the binary32 units fp_add, fp_mul and fp_div.
//
// Plusargs: +vectors=FILE (required), +unit=add|mul|div (default add).
// FILE has one vector per line, four hex words: `op a b y`, op 0 for a + b
// and 1 for a - b (the adder's sub input; ignored by mul and div), y the
// expected result word. One vector is presented per clock; the output of
// vector i is compared with its expected word LAT cycles later (LAT from
// fp_latency.vh), just before the edge at which vector i + LAT is sampled.
// Only the selected unit is clocked and driven.
//
// Output: the first MAX_SHOW mismatches, one line each, then exactly one
// line `vectors N mismatches M`.
`include "fp_latency.vh"

module tb_fp;
    localparam MAX_SHOW = 10;
    localparam RING = 16;  // > every latency

    reg clk = 1'b0;
    reg [31:0] a_add = 0, b_add = 0, a_mul = 0, b_mul = 0, a_div = 0, b_div = 0;
    reg sub_add = 1'b0;
    reg en_add = 1'b0, en_mul = 1'b0, en_div = 1'b0;
    wire [31:0] y_add, y_mul, y_div;
    wire clk_add = clk & en_add;
    wire clk_mul = clk & en_mul;
    wire clk_div = clk & en_div;

    fp_add u_add (.clk(clk_add), .a(a_add), .b(b_add), .sub(sub_add), .y(y_add));
    fp_mul u_mul (.clk(clk_mul), .a_in(a_mul), .b_in(b_mul), .y(y_mul));
    fp_div u_div (.clk(clk_div), .a_in(a_div), .b_in(b_div), .y(y_div));

    reg [8*1024-1:0] path;
    reg [8*8-1:0] unit;
    integer fd, r, lat, n, mism, cycle, j;
    reg more;
    reg [31:0] op, va, vb, vy, got;
    reg [31:0] q_op [0:RING-1];
    reg [31:0] q_a  [0:RING-1];
    reg [31:0] q_b  [0:RING-1];
    reg [31:0] q_y  [0:RING-1];

    initial begin
        if (!$value$plusargs("vectors=%s", path)) begin
            $display("error: missing +vectors=FILE");
            $finish;
        end
        if (!$value$plusargs("unit=%s", unit)) unit = "add";
        if (unit == "add") begin
            en_add = 1'b1;
            lat = `FP_ADD_LAT;
        end else if (unit == "mul") begin
            en_mul = 1'b1;
            lat = `FP_MUL_LAT;
        end else if (unit == "div") begin
            en_div = 1'b1;
            lat = `FP_DIV_LAT;
        end else begin
            $display("error: unknown +unit=%0s (add, mul or div)", unit);
            $finish;
        end
        fd = $fopen(path, "r");
        if (fd == 0) begin
            $display("error: cannot open %0s", path);
            $finish;
        end

        n = 0;
        mism = 0;
        more = 1'b1;
        // clk is low at the top of each cycle: check vector cycle - lat,
        // present vector `cycle`, then one rising and one falling edge.
        for (cycle = 0; more || cycle < n + lat; cycle = cycle + 1) begin
            if (cycle >= lat && cycle - lat < n) begin
                j = (cycle - lat) % RING;
                got = (unit == "add") ? y_add : (unit == "mul") ? y_mul : y_div;
                if (got !== q_y[j]) begin
                    mism = mism + 1;
                    if (mism <= MAX_SHOW)
                        $display("mismatch vector %0d: op %0h a %h b %h got %h expected %h",
                                 cycle - lat, q_op[j], q_a[j], q_b[j], got, q_y[j]);
                end
            end
            if (more) begin
                r = $fscanf(fd, " %h %h %h %h", op, va, vb, vy);
                if (r == 4) begin
                    j = n % RING;
                    q_op[j] = op;
                    q_a[j] = va;
                    q_b[j] = vb;
                    q_y[j] = vy;
                    n = n + 1;
                    if (en_add) begin
                        a_add = va;
                        b_add = vb;
                        sub_add = op[0];
                    end
                    if (en_mul) begin
                        a_mul = va;
                        b_mul = vb;
                    end
                    if (en_div) begin
                        a_div = va;
                        b_div = vb;
                    end
                end else
                    more = 1'b0;
            end
            #1 clk = 1'b1;
            #1 clk = 1'b0;
        end
        $fclose(fd);
        $display("vectors %0d mismatches %0d", n, mism);
        $finish;
    end
endmodule
