// SpyReport: lcm-spy (lcm.spy.Spy) started in this JVM, and what its window shows read back from the
// window itself: every --every-s seconds the rows of its channel table (the JTable lcm-spy draws:
// channel, type, messages, Hz, ...) are appended to a CSV file (t_s,channel,type,messages,hz); after
// --after-s seconds it exits. `./snapnav spy --report FILE --report-after-s S` runs it, so a test (or a
// lab without a person at the screen) can check what lcm-spy shows against what was published.
//   java -cp ... SpyReport --out FILE --after-s S [--every-s 1] [-- LCM-SPY ARGS...]
import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.io.FileWriter;
import java.io.PrintWriter;
import java.util.ArrayList;
import java.util.List;
import javax.swing.JTable;
import javax.swing.SwingUtilities;
import javax.swing.table.TableModel;

public class SpyReport {
  private static JTable findTable(Component c) {
    if (c instanceof JTable) return (JTable) c;
    if (c instanceof Container) {
      for (Component child : ((Container) c).getComponents()) {
        JTable t = findTable(child);
        if (t != null) return t;
      }
    }
    return null;
  }

  private static int column(TableModel m, String name) {
    for (int i = 0; i < m.getColumnCount(); ++i) {
      if (m.getColumnName(i).trim().equalsIgnoreCase(name)) return i;
    }
    return -1;
  }

  // The channel table's rows as CSV lines "t_s,channel,type,messages,hz" (read on the Swing thread).
  private static List<String> rows(double t) throws Exception {
    final List<String> out = new ArrayList<>();
    final String[] error = {null};
    SwingUtilities.invokeAndWait(() -> {
      JTable table = null;
      for (Frame f : Frame.getFrames()) {
        if (table == null && f.isVisible()) table = findTable(f);
      }
      if (table == null) {
        error[0] = "no lcm-spy window with a channel table";
        return;
      }
      TableModel m = table.getModel();
      int ch = column(m, "Channel"), type = column(m, "Type"), n = column(m, "Num Msgs"), hz = column(m, "Hz");
      if (ch < 0 || n < 0 || hz < 0) {
        error[0] = "lcm-spy's table has no Channel, Num Msgs or Hz column";
        return;
      }
      for (int r = 0; r < m.getRowCount(); ++r) {
        out.add(String.format("%.1f,%s,%s,%s,%s", t, m.getValueAt(r, ch), type < 0 ? "" : m.getValueAt(r, type),
                              String.valueOf(m.getValueAt(r, n)).trim(), String.valueOf(m.getValueAt(r, hz)).trim()));
      }
    });
    if (error[0] != null) throw new IllegalStateException(error[0]);
    return out;
  }

  public static void main(String[] args) throws Exception {
    String out = null;
    double after = 0, every = 1;
    List<String> spyArgs = new ArrayList<>();
    for (int i = 0; i < args.length; ++i) {
      if (args[i].equals("--out") && i + 1 < args.length) out = args[++i];
      else if (args[i].equals("--after-s") && i + 1 < args.length) after = Double.parseDouble(args[++i]);
      else if (args[i].equals("--every-s") && i + 1 < args.length) every = Double.parseDouble(args[++i]);
      else if (args[i].equals("--")) {
        for (++i; i < args.length; ++i) spyArgs.add(args[i]);
      } else {
        System.err.println("SpyReport: unknown argument " + args[i]
                           + "\nusage: SpyReport --out FILE --after-s S [--every-s 1] [-- LCM-SPY ARGS...]");
        System.exit(2);
      }
    }
    if (out == null || !(after > 0) || !(every > 0)) {
      System.err.println("SpyReport: --out FILE and a positive --after-s are required");
      System.exit(2);
    }
    lcm.spy.Spy.main(spyArgs.toArray(new String[0]));
    long start = System.nanoTime();
    try (PrintWriter w = new PrintWriter(new FileWriter(out))) {
      w.println("t_s,channel,type,messages,hz");
      for (double t = every; t <= after + 1e-9; t += every) {
        long wait = start + (long) (t * 1e9) - System.nanoTime();
        if (wait > 0) Thread.sleep(wait / 1_000_000, (int) (wait % 1_000_000));
        for (String row : rows(t)) w.println(row);
        w.flush();
      }
    } catch (Exception e) {
      System.err.println("SpyReport: " + e.getMessage());
      System.exit(1);
    }
    System.err.println("SpyReport: lcm-spy's channel table every " + every + " s for " + after + " s in " + out);
    System.exit(0);
  }
}
