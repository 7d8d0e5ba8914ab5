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
    // ros2 launch ends nodes with SIGINT, then SIGTERM.
    if let Err(e) = ctrlc::set_handler(move || stopper.stop()) {
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
