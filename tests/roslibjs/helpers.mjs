// The field's browser client (npm roslib 2.1.0) against a rosbridge server, for
// tests/integration/test_roslibjs.py: each of roslibjs's Ros helpers, then one publish/subscribe
// round, one service call and one action goal round, printed as one JSON object on stdout:
//   {"helpers": {name: {"ok": answer} | {"error": text}}, "decoded": ..., "pubsub": ..., ...}
// Every answer is printed as roslibjs hands it to its callback; the test compares it.
//
//   node helpers.mjs ws://127.0.0.1:9090 '<plan as JSON>'
//
// The plan names what to ask about (the test knows the graph):
//   node, topic, topic_type, service, service_type, message_type, param: {name, value},
//   pubsub: {topic, type, msg},                     a roslibjs publisher and a roslibjs subscriber
//   service_call: {name, type, args, provide},      provide: {response, echo_into}: a second roslibjs
//                                                   client serves it (the request as JSON text in echo_into)
//   action: {name, type, goal, provide},            provide: a second roslibjs client serves it
import * as ROSLIB from "roslib";

const TIMEOUT_MS = 10000;
const [url, planText] = process.argv.slice(2);
if (!url || !planText) {
  console.error("usage: node helpers.mjs ws://HOST:PORT '<plan JSON>'");
  process.exit(2);
}
const plan = JSON.parse(planText);

function within(promise, what) {
  let timer;
  const late = new Promise((resolve) => {
    timer = setTimeout(() => resolve({ error: `no answer in ${TIMEOUT_MS} ms (${what})` }), TIMEOUT_MS);
  });
  return Promise.race([promise, late]).finally(() => clearTimeout(timer));
}

async function connect() {
  const ros = new ROSLIB.Ros({});
  const opened = new Promise((resolve, reject) => {
    ros.on("connection", resolve);
    ros.on("error", (e) => reject(new Error(`cannot connect to ${url}: ${e?.message ?? e}`)));
  });
  await ros.connect(url);
  await opened;
  return ros;
}

// A helper's answer: {"ok": what its callback got} or {"error": what its failedCallback got}
function ask(call) {
  return within(
    new Promise((resolve) => call((ok) => resolve({ ok }), (error) => resolve({ error: String(error) }))),
    "helper",
  );
}

async function helpers(ros) {
  const calls = {
    getTopics: (ok, err) => ros.getTopics(ok, err),
    getServices: (ok, err) => ros.getServices(ok, err),
    getNodes: (ok, err) => ros.getNodes(ok, err),
    getNodeDetails: (ok, err) => ros.getNodeDetails(plan.node, ok, err),
    getParams: (ok, err) => ros.getParams(ok, err),
    getTopicType: (ok, err) => ros.getTopicType(plan.topic, ok, err),
    getServiceType: (ok, err) => ros.getServiceType(plan.service, ok, err),
    getTopicsForType: (ok, err) => ros.getTopicsForType(plan.topic_type, ok, err),
    getServicesForType: (ok, err) => ros.getServicesForType(plan.service_type, ok, err),
    getMessageDetails: (ok, err) => ros.getMessageDetails(plan.message_type, ok, err),
    getServiceRequestDetails: (ok, err) => ros.getServiceRequestDetails(plan.service_type, ok, err),
    getServiceResponseDetails: (ok, err) => ros.getServiceResponseDetails(plan.service_type, ok, err),
    getTopicsAndRawTypes: (ok, err) => ros.getTopicsAndRawTypes(ok, err),
    getActionServers: (ok, err) => ros.getActionServers(ok, err),
    // Topic.getPublishers: the one rosapi call of roslibjs outside Ros (it names /rosapi/publishers)
    "Topic.getPublishers": (ok, err) =>
      new ROSLIB.Topic({ ros, name: plan.topic, messageType: plan.topic_type }).getPublishers(ok, err),
  };
  if (plan.param) {
    // Param: roslibjs's other rosapi calls (rosapi/set_param, rosapi/get_param), in this order
    const param = new ROSLIB.Param({ ros, name: plan.param.name });
    calls["Param.set"] = (ok, err) => param.set(plan.param.value, ok, err);
    calls["Param.get"] = (ok, err) => param.get(ok, err);
  }
  const out = {};
  for (const [name, call] of Object.entries(calls)) {
    out[name] = await ask(call);
  }
  return out;
}

async function pubsub(ros, spec) {
  const listener = await connect();
  try {
    const sub = new ROSLIB.Topic({ ros: listener, name: spec.topic, messageType: spec.type });
    const got = new Promise((resolve) => sub.subscribe((msg) => resolve({ ok: msg })));
    const pub = new ROSLIB.Topic({ ros, name: spec.topic, messageType: spec.type });
    pub.advertise();
    // until the subscription is in place on the server, a message may be lost: publish until one arrives
    const timer = setInterval(() => pub.publish(spec.msg), 100);
    try {
      return await within(got, "subscribe");
    } finally {
      clearInterval(timer);
      sub.unsubscribe();
      pub.unadvertise();
    }
  } finally {
    listener.close();
  }
}

async function serviceCall(ros, spec) {
  let server = null;
  try {
    if (spec.provide) {
      server = await connect();
      const provided = new ROSLIB.Service({ ros: server, name: spec.name, serviceType: spec.type });
      await provided.advertise((request, response) => {
        Object.assign(response, spec.provide.response);
        if (spec.provide.echo_into) response[spec.provide.echo_into] = JSON.stringify(request);
        return true;
      });
    }
    const client = new ROSLIB.Service({ ros, name: spec.name, serviceType: spec.type });
    // a service advertised by a client, or on the graph, may take a moment to be seen: retry a failure
    const deadline = Date.now() + TIMEOUT_MS;
    for (;;) {
      const answer = await ask((ok, err) => client.callService(spec.args, ok, err));
      if ("ok" in answer || Date.now() > deadline) return answer;
      await new Promise((r) => setTimeout(r, 200));
    }
  } finally {
    server?.close();
  }
}

async function actionRound(ros, spec) {
  let server = null;
  try {
    if (spec.provide) {
      server = await connect();
      const provided = new ROSLIB.Action({ ros: server, name: spec.name, actionType: spec.type });
      provided.advertise(
        (goal, id) => {
          for (const feedback of spec.provide.feedback) provided.sendFeedback(id, feedback);
          provided.setSucceeded(id, spec.provide.result(goal));
        },
        () => {},
      );
    }
    const action = new ROSLIB.Action({ ros, name: spec.name, actionType: spec.type });
    const deadline = Date.now() + TIMEOUT_MS;
    for (;;) {
      const feedback = [];
      const answer = await within(
        new Promise((resolve) => {
          action.sendGoal(
            spec.goal,
            (result) => resolve({ ok: { result, feedback } }),
            (f) => feedback.push(f),
            (error) => resolve({ error: String(error) }),
          );
        }),
        "action",
      );
      if ("ok" in answer || Date.now() > deadline) return answer;
      await new Promise((r) => setTimeout(r, 200));
    }
  } finally {
    server?.close();
  }
}

async function main() {
  const ros = await connect();
  const out = { roslib: ROSLIB.REVISION };
  out.helpers = await helpers(ros);
  const details = out.helpers.getMessageDetails;
  if ("ok" in details) {
    try {
      out.decoded = { ok: ros.decodeTypeDefs(details.ok) };
    } catch (e) {
      out.decoded = { error: String(e) };
    }
  }
  if (plan.pubsub) out.pubsub = await pubsub(ros, plan.pubsub);
  if (plan.service_call) out.service_call = await serviceCall(ros, plan.service_call);
  if (plan.action) {
    const spec = { ...plan.action };
    // the provided action's answer: the goal's order, as Fibonacci's sequence would start
    if (spec.provide) {
      spec.provide = {
        feedback: [{ sequence: [0] }, { sequence: [0, 1] }],
        result: (goal) => ({ sequence: Array.from({ length: goal.order }, (_, i) => i) }),
      };
    }
    out.action = await actionRound(ros, spec);
  }
  ros.close();
  process.stdout.write(JSON.stringify(out) + "\n");
}

main().then(
  () => process.exit(0),
  (e) => {
    process.stdout.write(JSON.stringify({ fatal: String(e?.stack ?? e) }) + "\n");
    process.exit(1);
  },
);
