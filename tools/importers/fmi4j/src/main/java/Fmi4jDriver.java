import java.io.BufferedWriter;
import java.io.File;
import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Paths;
import java.util.ArrayList;
import java.util.List;

import no.ntnu.ihb.fmi4j.FmiStatus;
import no.ntnu.ihb.fmi4j.importer.fmi2.CoSimulationFmu;
import no.ntnu.ihb.fmi4j.importer.fmi2.CoSimulationSlave;
import no.ntnu.ihb.fmi4j.importer.fmi2.Fmu;
import no.ntnu.ihb.fmi4j.modeldescription.DefaultExperiment;
import no.ntnu.ihb.fmi4j.modeldescription.variables.Causality;
import no.ntnu.ihb.fmi4j.modeldescription.variables.TypedScalarVariable;
import no.ntnu.ihb.fmi4j.modeldescription.variables.VariableType;

/**
 * Runs an FMI 2.0 Co-Simulation FMU's default experiment with FMI4j
 * (info.laht.fmi4j:fmi-import) and writes its outputs as CSV.
 *
 * <pre>
 *   java -cp CLASSES:LIB/* Fmi4jDriver FMU OUT.csv [--output-interval SECONDS]
 *   java -cp CLASSES:LIB/* Fmi4jDriver --check      (the FMI4j classes load)
 * </pre>
 *
 * The FMU is stepped from the default experiment's startTime to its stopTime with
 * its stepSize; a row (time, then every output in model-description order) is
 * written after initialization and then at every communication point that is a
 * multiple of the output interval (default: every step), plus the last one.
 *
 * Work-arounds for defects of FMI4j 0.38.0, all kept here and none in the FMU:
 * <ul>
 *   <li>its getFMUstate passes an uninitialized pointer to fmi2GetFMUstate
 *       (FMI requires *FMUstate == NULL for a new state): never called here;</li>
 *   <li>its getBooleanStatus (and getRealStatus) have no native counterpart
 *       (UnsatisfiedLinkError): never called here;</li>
 *   <li>CoSimulationSlave.doStep refuses any step whose end t + h exceeds
 *       stopTime by even 1 ulp, so the communication points are computed as
 *       start + k * stepSize (no accumulation), the step count is rounded, and
 *       the last point is stopTime exactly (stopTime - t is exact for t near
 *       stopTime, so t + (stopTime - t) == stopTime);</li>
 *   <li>its doStep only logs (through slf4j, not configured here) why it
 *       refused a step, so failures are reported here with the times.</li>
 * </ul>
 */
public final class Fmi4jDriver {

    private static void die(String message) {
        System.err.println("Fmi4jDriver: " + message);
        System.exit(1);
    }

    private static String usage() {
        return "usage: Fmi4jDriver FMU OUT.csv [--output-interval SECONDS]";
    }

    public static void main(String[] args) throws IOException {
        if (args.length == 1 && args[0].equals("--check")) {
            // For install.sh: the FMI4j classes resolve and its native library is in the jar.
            Class<?> c = Fmu.class;
            if (c.getClassLoader().getResource("native/fmi/linux64/libfmi4j-import.so") == null) {
                die("FMI4j's native library native/fmi/linux64/libfmi4j-import.so is not on the class path");
            }
            System.out.println("Fmi4jDriver: FMI4j from " + c.getProtectionDomain().getCodeSource().getLocation());
            return;
        }
        if (args.length != 2 && args.length != 4) die(usage());
        File fmuFile = new File(args[0]);
        String outPath = args[1];
        Double outputInterval = null;
        if (args.length == 4) {
            if (!args[2].equals("--output-interval")) die(usage());
            outputInterval = Double.parseDouble(args[3]);
        }
        if (!fmuFile.isFile()) die("no such FMU: " + fmuFile);

        long wallStart = System.nanoTime();
        Fmu fmu = Fmu.from(fmuFile);
        try {
            if (!fmu.getSupportsCoSimulation()) die(fmuFile + " does not support Co-Simulation");
            CoSimulationFmu cs = fmu.asCoSimulationFmu();
            DefaultExperiment de = cs.getModelDescription().getDefaultExperiment();
            if (de == null) die(fmuFile + " has no DefaultExperiment");
            double start = de.getStartTime(), stop = de.getStopTime(), h = de.getStepSize();
            double tol = de.getTolerance();
            if (!(h > 0) || !(stop > start)) {
                die(String.format("DefaultExperiment startTime=%s stopTime=%s stepSize=%s is not usable",
                        start, stop, h));
            }
            double span = (stop - start) / h;
            long n = Math.round(span);
            if (n < 1 || Math.abs(span - n) > 1e-6) {
                die(String.format("stopTime - startTime = %s is not a multiple of stepSize = %s", stop - start, h));
            }
            long every = 1;
            if (outputInterval != null) {
                double r = outputInterval / h;
                every = Math.round(r);
                if (every < 1 || Math.abs(r - every) > 1e-6) {
                    die("--output-interval " + outputInterval + " is not a multiple of stepSize " + h);
                }
            }

            // Outputs in model-description order, grouped by type for the read calls.
            List<TypedScalarVariable<?>> outputs = new ArrayList<>();
            for (TypedScalarVariable<?> v : cs.getModelDescription().getModelVariables().getVariables()) {
                if (v.getCausality() == Causality.OUTPUT) outputs.add(v);
            }
            int m = outputs.size();
            if (m == 0) die(fmuFile + " has no outputs");
            VariableType[] types = new VariableType[m];
            long[] vr = new long[m];
            for (int i = 0; i < m; i++) {
                types[i] = outputs.get(i).getType();
                vr[i] = outputs.get(i).getValueReference();
                if (types[i] == VariableType.STRING) die("String output " + outputs.get(i).getName() + " is not supported");
            }

            CoSimulationSlave slave = cs.newInstance();
            try (BufferedWriter out = Files.newBufferedWriter(Paths.get(outPath), StandardCharsets.UTF_8)) {
                // No simpleSetup(): every call is made explicitly so that a failure says which.
                if (!slave.setupExperiment(start, stop, tol)) die("setupExperiment failed: " + slave.getLastStatus());
                if (!slave.enterInitializationMode()) die("enterInitializationMode failed: " + slave.getLastStatus());
                if (!slave.exitInitializationMode()) die("exitInitializationMode failed: " + slave.getLastStatus());

                StringBuilder header = new StringBuilder("time");
                for (TypedScalarVariable<?> v : outputs) header.append(',').append(csvName(v.getName()));
                out.write(header.toString());
                out.newLine();

                long[] one = new long[1];
                double[] real = new double[1];
                int[] integer = new int[1];
                boolean[] bool = new boolean[1];
                StringBuilder row = new StringBuilder();
                long rows = 0;
                double t = start;
                for (long k = 0; ; k++) {
                    if (k % every == 0 || k == n) {
                        row.setLength(0);
                        row.append(t);
                        for (int i = 0; i < m; i++) {
                            one[0] = vr[i];
                            FmiStatus s;
                            row.append(',');
                            if (types[i] == VariableType.REAL) {
                                s = slave.readReal(one, real);
                                row.append(real[0]);
                            } else if (types[i] == VariableType.BOOLEAN) {
                                s = slave.readBoolean(one, bool);
                                row.append(bool[0] ? 1 : 0);
                            } else {
                                s = slave.readInteger(one, integer);
                                row.append(integer[0]);
                            }
                            if (s != FmiStatus.OK) die("reading " + outputs.get(i).getName() + " at t=" + t + ": " + s);
                        }
                        out.write(row.toString());
                        out.newLine();
                        rows++;
                    }
                    if (k == n) break;
                    double next = (k + 1 == n) ? stop : start + (k + 1) * h;
                    if (!slave.doStep(t, next - t)) {
                        die(String.format("doStep(%.17g, %.17g) failed (status %s; stopTime %.17g)",
                                t, next - t, slave.getLastStatus(), stop));
                    }
                    t = next;
                }
                if (!slave.terminate()) die("terminate failed: " + slave.getLastStatus());
                System.out.printf("Fmi4jDriver: %s: %d steps of %s from %s to %s, %d rows x %d outputs -> %s (%.1f s)%n",
                        fmu.getModelName(), n, h, start, stop, rows, m, outPath,
                        (System.nanoTime() - wallStart) * 1e-9);
            } finally {
                slave.close();
            }
        } finally {
            fmu.close();
        }
    }

    /** CSV field for a variable name: quoted when it holds a comma or a quote. */
    private static String csvName(String name) {
        if (name.indexOf(',') < 0 && name.indexOf('"') < 0) return name;
        return '"' + name.replace("\"", "\"\"") + '"';
    }
}
