//! `whycode_node`: the ROS 2 node. See ros2/README.md.

use std::process::ExitCode;
use whycode_ros2::args::{RosArgs, USAGE};
use whycode_ros2::node;

fn main() -> ExitCode {
    let args = match RosArgs::parse(std::env::args().skip(1)) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("whycode_node: {e}");
            return ExitCode::from(2);
        }
    };
    if args.help {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    if args.version {
        println!("whycode_node {}", env!("CARGO_PKG_VERSION"));
        return ExitCode::SUCCESS;
    }
    let (controller, control) = node::control_channel();
    let stopper = controller.clone();
    // ros2 launch ends nodes with SIGINT, then SIGTERM: the first finishes
    // the frame in hand and logs the summary, a second one ends at once.
    let signals = std::sync::atomic::AtomicUsize::new(0);
    let handler = move || {
        if signals.fetch_add(1, std::sync::atomic::Ordering::SeqCst) == 0 {
            stopper.stop();
        } else {
            std::process::exit(130);
        }
    };
    if let Err(e) = ctrlc::set_handler(handler) {
        eprintln!("whycode_node: cannot handle signals: {e}");
        return ExitCode::FAILURE;
    }
    match node::run(&args, controller, control) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("whycode_node: {e}");
            ExitCode::from(2)
        }
    }
}
