// Test helper for test_lcm_spy.cpp: proves that the generated Java types (the jar lcm-spy
// loads) decode what the C++ side publishes. Subscribes to CHANNEL, prints "READY", then
// prints the first heartbeat field by field and exits 0 (1: decode error, 2: timeout).
//
//   java -cp lcm.jar:openvcu-lcm-types.jar:DIR HeartbeatProbe URL CHANNEL TIMEOUT_MS

import java.io.IOException;
import lcm.lcm.LCM;
import lcm.lcm.LCMDataInputStream;
import lcm.lcm.LCMSubscriber;
import openvcu_lcm.heartbeat_t;

public final class HeartbeatProbe implements LCMSubscriber {
    @Override
    public void messageReceived(LCM source, String channel, LCMDataInputStream input) {
        try {
            heartbeat_t message = new heartbeat_t(input);
            StringBuilder out = new StringBuilder();
            out.append("service=").append(message.service).append('\n');
            out.append("instance=").append(message.instance).append('\n');
            out.append("pid=").append(message.pid).append('\n');
            out.append("uptime_ms=").append(message.uptime_ms).append('\n');
            for (int i = 0; i < message.num_counters; ++i) {
                out.append("counter=").append(message.counter_names[i]).append(':')
                   .append(message.counter_values[i]).append('\n');
            }
            out.append("status=").append(message.status).append('\n');
            out.append("END\n");
            System.out.print(out);
            System.out.flush();
            System.exit(0);
        } catch (IOException e) {
            System.out.println("DECODE-ERROR " + e.getMessage());
            System.out.flush();
            System.exit(1);
        }
    }

    public static void main(String[] args) throws Exception {
        if (args.length != 3) {
            System.err.println("usage: HeartbeatProbe URL CHANNEL TIMEOUT_MS");
            System.exit(64);
        }
        LCM lcm = new LCM(args[0]);
        lcm.subscribe(args[1], new HeartbeatProbe());
        System.out.println("READY");
        System.out.flush();
        Thread.sleep(Long.parseLong(args[2]));
        System.out.println("TIMEOUT");
        System.out.flush();
        System.exit(2);
    }
}
