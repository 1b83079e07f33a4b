// Testbench of ekf_core: reads corrections from +vectors=FILE, one per line,
// 44 hexadecimal binary32 words: the input bank in address order (X- 3,
// P- 9, H 6, R 4, z 2, h(X-) 2) and the expected results (G 6, X+ 3, P+ 9)
// of the software f32 schedule. For each it writes the bank, pulses start,
// counts the clock edges until done (and the cycles spent in each FSM
// state), reads G, X+ and P+ back and compares the words. Prints the first
// mismatches, then one summary line:
//   corrections N mismatches M cycles MIN MAX states W M1 M2 MA A D
// (the state counts are those of the last correction).

`timescale 1ns / 1ps

module tb_core;
    reg clk = 1'b0;
    always #10 clk = ~clk;  // 50 MHz

    reg rst = 1'b1, wr_en = 1'b0, start = 1'b0;
    reg [6:0] wr_addr = 7'd0, rd_addr = 7'd0;
    reg [31:0] wr_data = 32'd0;
    wire [31:0] rd_data;
    wire busy, done;
    wire [2:0] state;

    ekf_core dut (
        .clk(clk), .rst(rst), .wr_en(wr_en), .wr_addr(wr_addr), .wr_data(wr_data),
        .rd_addr(rd_addr), .rd_data(rd_data), .start(start), .busy(busy),
        .done(done), .state(state)
    );

    // Result addresses in the vector's order: G, X+, P+.
    function [6:0] result_addr(input integer i);
        if (i < 6) result_addr = 45 + i;
        else if (i < 9) result_addr = 56 + (i - 6);
        else result_addr = 77 + (i - 9);
    endfunction

    integer fd, n, i, got, corrections, mismatches, cycles, min_cycles, max_cycles;
    integer states [0:5];
    reg [31:0] words [0:43];
    reg [1023:0] path;

    initial begin
        if (!$value$plusargs("vectors=%s", path)) begin
            $display("error: no +vectors=FILE");
            $finish;
        end
        fd = $fopen(path, "r");
        if (fd == 0) begin
            $display("error: cannot open %0s", path);
            $finish;
        end
        corrections = 0;
        mismatches = 0;
        min_cycles = 1 << 30;
        max_cycles = 0;
        repeat (2) @(posedge clk);
        rst <= 1'b0;
        n = 44;
        while (n == 44) begin
            n = 0;
            for (i = 0; i < 44; i = i + 1)
                n = n + $fscanf(fd, "%h", words[i]);
            if (n == 44) begin
                // Write the input bank.
                for (i = 0; i < 26; i = i + 1) begin
                    @(negedge clk);
                    wr_en = 1'b1;
                    wr_addr = i;
                    wr_data = words[i];
                end
                @(negedge clk);
                wr_en = 1'b0;
                start = 1'b1;
                @(posedge clk);  // the edge that samples start
                @(negedge clk);
                start = 1'b0;
                cycles = 0;
                for (i = 0; i < 6; i = i + 1) states[i] = 0;
                // Count the edges until done; the state of each cycle.
                while (!done) begin
                    states[state] = states[state] + 1;
                    @(posedge clk);
                    cycles = cycles + 1;
                    @(negedge clk);
                end
                if (cycles < min_cycles) min_cycles = cycles;
                if (cycles > max_cycles) max_cycles = cycles;
                for (i = 0; i < 18; i = i + 1) begin
                    rd_addr = result_addr(i);
                    #1;
                    if (rd_data !== words[26 + i]) begin
                        if (mismatches < 10)
                            $display("mismatch: correction %0d result %0d got %h expected %h",
                                     corrections, i, rd_data, words[26 + i]);
                        mismatches = mismatches + 1;
                    end
                end
                corrections = corrections + 1;
            end
        end
        $display("corrections %0d mismatches %0d cycles %0d %0d states %0d %0d %0d %0d %0d %0d",
                 corrections, mismatches, min_cycles, max_cycles,
                 states[0], states[1], states[2], states[3], states[4], states[5]);
        $finish;
    end
endmodule
